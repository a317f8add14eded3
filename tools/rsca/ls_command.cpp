// rsca ls apps|nodes|devices|installed
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "commands.hpp"
#include "domain_client.hpp"
#include "exit_codes.hpp"

namespace rsca::cli {
namespace {

using control::Json;

void print_apps(const Json &r) {
  fmt::print("{:<24} {:<24} {:<10} {}\n", "APPLICATION", "INSTALLED AS", "STATE", "COMPONENTS");
  for (const auto &a : r.at("applications")) {
    const Json exited = a.value("exited", Json::array());
    fmt::print("{:<24} {:<24} {:<10} {}{}\n", a.value("name", ""), a.value("installed", ""),
               a.value("state", ""), a.value("components", 0),
               exited.empty() ? "" : fmt::format("  (exited: {})", fmt::join(exited, ", ")));
  }
  // Left by an earlier run of the domain daemon (one that was killed): the domain cannot release
  // them, the operator can.
  const Json unknown = r.value("unknown", Json::array());
  if (unknown.empty())
    return;
  fmt::print("\n{} component process(es) run that no application of this domain launched (an "
             "earlier run of the domain daemon did):\n",
             unknown.size());
  for (const auto &u : unknown)
    fmt::print("  pid {:<8} {}\n", u.value("pid", 0), u.value("address", ""));
}

void print_installed(const Json &r) {
  fmt::print("{:<24} {:<10} {}\n", "INSTALLED", "COMPONENTS", "SAD");
  for (const auto &a : r.at("applications"))
    fmt::print("{:<24} {:<10} {}\n", a.value("name", ""), a.value("components", 0),
               a.value("sad", ""));
}

void print_nodes(const Json &r) {
  fmt::print("{:<16} {:<8} {:<8} {}\n", "NODE", "PID", "DEVICES", "ADDRESS");
  for (const auto &n : r.at("nodes"))
    fmt::print("{:<16} {:<8} {:<8} {}\n", n.value("name", ""), n.value("pid", 0L),
               n.value("devices", 0), n.value("address", ""));
}

void print_devices(const Json &r) {
  fmt::print("{:<20} {:<8} {:<6} {:>28} {:>34}\n", "DEVICE", "NODE", "KIND",
             "CPU % (total/alloc/free)", "MEMORY MiB (total/alloc/free)");
  for (const auto &d : r.at("devices")) {
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

void print_channels(const Json &r) {
  fmt::print("{:<20} {:<10} {:>10} {:>11}  {}\n", "CHANNEL", "OWNER", "PUBLISHERS", "SUBSCRIBERS",
             "TOPIC");
  for (const auto &c : r.at("channels")) {
    fmt::print("{:<20} {:<10} {:>10} {:>11}  {}\n", c.value("name", ""),
               c.value("operator", false) ? "operator" : "apps", c.value("publishers", 0),
               c.value("subscribers", 0), c.value("topic", ""));
    for (const auto &m : c.at("members"))
      fmt::print("  {:<10} {}/{}.{}{}\n", m.value("role", ""), m.value("application", ""),
                 m.value("component", ""), m.value("port", ""),
                 m.value("filter", "").empty() ? "" : "  filter: " + m.value("filter", ""));
  }
}

std::string end_state(const Json &state) {
  if (state.is_null())
    return "-";
  const int missed = state.value("deadline_missed", 0);
  return fmt::format("{} matched, {} samples{}{}", state.value("matched", 0),
                     state.value("samples", 0),
                     missed == 0 ? "" : fmt::format(", {} deadlines missed", missed),
                     state.value("in_host", false) ? " (in-host)" : "");
}

void print_connections(const Json &r) {
  for (const auto &c : r.at("connections")) {
    const std::string uses = c.value("uses", ""), provides = c.value("provides", "");
    const std::string topic = c.value("topic", "");
    fmt::print("{}/{}: {} -> {}  [{}]\n", c.value("application", ""), c.value("id", ""),
               uses.empty() ? "(channel)" : uses, provides.empty() ? "(channel)" : provides,
               topic.empty() ? "calls " + c.value("repid", "") : topic);
    if (topic.empty()) {
      // A uses port calling a component's supported interface: control calls, no DDS QoS.
      const Json &state = c.at("uses_state");
      fmt::print("  uses: {}\n",
                 state.is_null() ? "-" : fmt::format("{} calls", state.value("calls", 0)));
      continue;
    }
    const auto &q = c.at("qos");
    fmt::print("  qos {} {} {}{}\n", q.value("reliability", ""), q.value("durability", ""),
               q.value("history", ""),
               q.contains("depth") ? fmt::format(" depth {}", q.at("depth").dump()) : "");
    if (c.value("state", "") == "pending") {
      fmt::print("  pending: {}\n", c.value("waiting_for", ""));
      continue;
    }
    fmt::print("  uses: {}   provides: {}\n", end_state(c.at("uses_state")),
               end_state(c.at("provides_state")));
  }
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
    struct View {
      const char *operation;
      void (*print)(const Json &);
    };
    const View view = *what == "nodes"         ? View{"domain.nodes", print_nodes}
                      : *what == "devices"     ? View{"domain.devices", print_devices}
                      : *what == "installed"   ? View{"domain.installed", print_installed}
                      : *what == "channels"    ? View{"channel.list", print_channels}
                      : *what == "connections" ? View{"connection.list", print_connections}
                                               : View{"app.list", print_apps};
    auto client = DomainClient::connect(global);
    if (!client) {
      fmt::print(stderr, "rsca ls: {}\n", client.error().to_string());
      exit_code = kFailed;
      return;
    }
    Json body = Json::object();
    if (!of_app->empty())
      body["app"] = *of_app;
    auto reply = client->call(view.operation, body, std::chrono::milliseconds(global.timeout_ms));
    if (!reply) {
      exit_code = report_failure(global, "ls", reply.error());
      return;
    }
    global.json ? print_json(*reply) : view.print(*reply);
    exit_code = kOk;
  });
}

} // namespace rsca::cli
