// rsca ls apps|nodes|devices|installed
#include <fmt/format.h>

#include "commands.hpp"
#include "domain_client.hpp"
#include "exit_codes.hpp"

namespace rsca::cli {
namespace {

using control::Json;

void print_apps(const Json &r) {
  fmt::print("{:<24} {:<24} {:<10} {}\n", "APPLICATION", "INSTALLED AS", "STATE", "COMPONENTS");
  for (const auto &a : r.at("applications"))
    fmt::print("{:<24} {:<24} {:<10} {}\n", a.value("name", ""), a.value("installed", ""),
               a.value("state", ""), a.value("components", 0));
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

} // namespace

void add_ls_command(CLI::App &app, const GlobalOptions &global, int &exit_code) {
  auto *cmd =
      app.add_subcommand("ls", "List what the domain holds: apps, nodes, devices or installed");
  auto what = std::make_shared<std::string>("apps");
  cmd->add_option("what", *what, "apps, nodes, devices or installed")
      ->check(CLI::IsMember({"apps", "nodes", "devices", "installed"}));
  cmd->callback([what, &global, &exit_code] {
    struct View {
      const char *operation;
      void (*print)(const Json &);
    };
    const View view = *what == "nodes"       ? View{"domain.nodes", print_nodes}
                      : *what == "devices"   ? View{"domain.devices", print_devices}
                      : *what == "installed" ? View{"domain.installed", print_installed}
                                             : View{"app.list", print_apps};
    auto client = DomainClient::connect(global);
    if (!client) {
      fmt::print(stderr, "rsca ls: {}\n", client.error().to_string());
      exit_code = kFailed;
      return;
    }
    auto reply =
        client->call(view.operation, Json::object(), std::chrono::milliseconds(global.timeout_ms));
    if (!reply) {
      exit_code = report_failure(global, "ls", reply.error());
      return;
    }
    global.json ? print_json(*reply) : view.print(*reply);
    exit_code = kOk;
  });
}

} // namespace rsca::cli
