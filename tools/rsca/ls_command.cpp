// rsca ls apps|nodes|devices|installed
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "commands.hpp"
#include "domain_client.hpp"
#include "exit_codes.hpp"
#include "protocol/application_ops.hpp"
#include "protocol/connection_ops.hpp"
#include "protocol/domain_ops.hpp"

namespace rsca::cli {
namespace {

namespace app_ops = protocol::application;
namespace connection_ops = protocol::connection;
namespace domain_ops = protocol::domain;
using control::Json;

void print_apps(const app_ops::ListReply &r) {
  fmt::print("{:<24} {:<24} {:<10} {}\n", "APPLICATION", "INSTALLED AS", "STATE", "COMPONENTS");
  for (const auto &a : r.applications)
    fmt::print("{:<24} {:<24} {:<10} {}{}{}\n", a.name, a.installed, a.state, a.components,
               a.exited.empty() ? "" : fmt::format("  (exited: {})", fmt::join(a.exited, ", ")),
               a.unreachable.empty()
                   ? ""
                   : fmt::format("  (unreachable: {})", fmt::join(a.unreachable, ", ")));
  // Left by an earlier run of the domain daemon (one that was killed): the domain cannot release
  // them, the operator can.
  if (r.unknown.empty())
    return;
  fmt::print("\n{} component process(es) run that no application of this domain launched (an "
             "earlier run of the domain daemon did):\n",
             r.unknown.size());
  for (const auto &u : r.unknown)
    fmt::print("  pid {:<8} {}\n", u.pid, u.address);
}

void print_installed(const domain_ops::InstalledReply &r) {
  fmt::print("{:<24} {:<10} {}\n", "INSTALLED", "COMPONENTS", "SAD");
  for (const auto &a : r.applications)
    fmt::print("{:<24} {:<10} {}\n", a.name, a.components, a.sad);
}

// A node's row, then a line per device of its DCD it did not start, with why.
void print_node(const domain_ops::NodeSummary &n, std::string_view state) {
  fmt::print("{:<16} {:<8} {:<8} {:<8} {}\n", n.name, n.pid, n.devices, state, n.address);
  for (const auto &f : n.failed_devices.value_or(std::vector<protocol::node::FailedDevice>{}))
    fmt::print("  not started: {} ({}): {}\n", f.id, f.softpkg, f.reason);
}

void print_nodes(const domain_ops::NodesReply &r) {
  fmt::print("{:<16} {:<8} {:<8} {:<8} {}\n", "NODE", "PID", "DEVICES", "STATE", "ADDRESS");
  for (const auto &n : r.nodes)
    print_node(n, "up");
  // Its lease ran out: it holds its devices and components until it is back.
  for (const auto &n : r.lost)
    print_node(n, "lost");
  for (const auto &refused : r.refused)
    fmt::print("refused: the endpoint at {} announced itself as a node in a form this domain does "
               "not take: {}\n",
               refused.address, refused.why);
}

void print_devices(const domain_ops::DevicesReply &r) {
  fmt::print("{:<20} {:<8} {:<6} {:>28} {:>34}\n", "DEVICE", "NODE", "KIND",
             "CPU % (total/alloc/free)", "MEMORY MiB (total/alloc/free)");
  for (const auto &d : r.devices) {
    auto cap = [&](const char *name) {
      const auto &c = d.at("capacity");
      if (!c.contains(name))
        return std::string("-");
      const auto &v = c.at(name);
      return fmt::format("{:.0f}/{:.0f}/{:.0f}", v.value("total", 0.0), v.value("allocated", 0.0),
                         v.value("free", 0.0));
    };
    fmt::print("{:<20} {:<8} {:<6} {:>28} {:>34}\n", d.value("id", ""), d.value("node", ""),
               d.value("kind", ""), cap("cpu_capacity"), cap("mem_capacity"));
  }
}

void print_channels(const connection_ops::ChannelsReply &r) {
  fmt::print("{:<20} {:<10} {:>10} {:>11}  {}\n", "CHANNEL", "OWNER", "PUBLISHERS", "SUBSCRIBERS",
             "TOPIC");
  for (const auto &c : r.channels) {
    fmt::print("{:<20} {:<10} {:>10} {:>11}  {}\n", c.name, c.operator_owned ? "operator" : "apps",
               c.publishers, c.subscribers, c.topic);
    for (const auto &m : c.members)
      fmt::print("  {:<10} {}/{}.{}{}\n", m.role, m.application, m.component, m.port,
                 m.filter.empty() ? "" : "  filter: " + m.filter);
  }
}

std::string end_state(const Json &state) {
  if (state.is_null())
    return "-";
  const int missed = state.value("deadline_missed", 0);
  return fmt::format("{} matched, {} samples{}{}", state.value("matched", 0),
                     state.value("samples", 0),
                     missed == 0 ? "" : fmt::format(", {} deadlines missed", missed),
                     state.value("in_host", false)     ? " (in-host)"
                     : state.value("relayed", false)   ? " (through the nodes)"
                     : state.value("same_host", false) ? " (same-host, shared memory)"
                     : state.value("tcp", false)       ? " (TCP stream)"
                                                       : "");
}

void print_connections(const connection_ops::ListReply &r) {
  for (const auto &c : r.connections) {
    fmt::print("{}/{}: {} -> {}  [{}]\n", c.application, c.id,
               c.uses.empty() ? "(channel)" : c.uses, c.provides.empty() ? "(channel)" : c.provides,
               c.topic.empty() ? "calls " + c.repid : c.topic);
    if (c.topic.empty()) {
      // A uses port calling a component's supported interface: control calls, no DDS QoS.
      const Json &state = c.uses_state;
      fmt::print("  uses: {}\n",
                 state.is_null() ? "-" : fmt::format("{} calls", state.value("calls", 0)));
      continue;
    }
    const auto &q = c.qos;
    fmt::print("  qos {} {} {}{}\n", q.value("reliability", ""), q.value("durability", ""),
               q.value("history", ""),
               q.contains("depth") ? fmt::format(" depth {}", q.at("depth").dump()) : "");
    if (c.state == connection_ops::ConnectionState::Pending) {
      fmt::print("  pending: {}\n", c.waiting_for.value_or(""));
      continue;
    }
    fmt::print("  uses: {}   provides: {}\n", end_state(c.uses_state), end_state(c.provides_state));
  }
}

// One view of `rsca ls`: the domain's reply to `Op`, printed by `print_text`.
template <control::Operation Op>
int list(const GlobalOptions &global, const typename Op::Request &request,
         void (*print_text)(const typename Op::Reply &)) {
  return call_and_print<Op>(global, "ls", request, std::chrono::milliseconds(global.timeout_ms),
                            print_text);
}

} // namespace

void add_ls_command(CLI::App &app, const GlobalOptions &global, int &exit_code) {
  auto *cmd =
      app.add_subcommand("ls", "List what the domain holds: apps, nodes, devices, installed, "
                               "channels or connections [APP]");
  auto what = std::make_shared<std::string>("apps");
  auto of_app = std::make_shared<std::string>();
  cmd->add_option("what", *what, "apps, nodes, devices, installed, channels or connections")
      ->check(CLI::IsMember({"apps", "nodes", "devices", "installed", "channels", "connections"}));
  cmd->add_option("app", *of_app, "connections: only this application's");
  cmd->callback([what, of_app, &global, &exit_code] {
    exit_code =
        *what == "nodes"         ? list<domain_ops::Nodes>(global, {}, print_nodes)
        : *what == "devices"     ? list<domain_ops::Devices>(global, {}, print_devices)
        : *what == "installed"   ? list<domain_ops::Installed>(global, {}, print_installed)
        : *what == "channels"    ? list<connection_ops::ListChannels>(global, {}, print_channels)
        : *what == "connections" ? list<connection_ops::List>(global, {*of_app}, print_connections)
                                 : list<app_ops::List>(global, {}, print_apps);
  });
}

} // namespace rsca::cli
