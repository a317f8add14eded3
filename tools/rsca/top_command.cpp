// rsca top [APP]: CPU, resident memory and threads of the daemons and of every process the nodes
// run, each node asked for its own (node.top) and the domain daemon for itself (domain.top), all at
// once. A node that does not answer is listed as unreachable; the others are shown all the same.
// So is a node the domain has lost (its DDS lease ran out): it is not asked, and not left out
// either, since its devices and components are still the domain's.
#include <future>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "commands.hpp"
#include "domain_client.hpp"
#include "exit_codes.hpp"
#include "protocol/application_ops.hpp"
#include "protocol/domain_ops.hpp"
#include "protocol/node_ops.hpp"

namespace rsca::cli {
namespace {

namespace domain_ops = protocol::domain;
namespace node_ops = protocol::node;
using control::Json;

// One line of the table: a daemon, or a process a node runs.
struct Row {
  std::string host;
  std::string node; // "domain" for the domain daemon
  std::string what; // rsca-domaind, rsca-noded, or APPLICATION/COMPONENT
  std::string application;
  std::string component;
  node_ops::ProcessFigures figures;
};

struct Unreachable {
  std::string node;
  std::string error;
  bool lost = false; // the domain lost it: not asked
};

struct Table {
  std::vector<Row> rows;
  std::vector<Unreachable> unreachable;
};

using Pending = std::future<control::CallResult<Json>>;

void add_node(Table &table, const std::string &node, Pending &pending, const std::string &app) {
  auto reply = control::reply_of<node_ops::Top>(pending.get());
  if (!reply) {
    table.unreachable.push_back({node, reply.error().message, false});
    return;
  }
  if (app.empty())
    table.rows.push_back({reply->host, reply->node, "rsca-noded", "", "", reply->daemon});
  for (const auto &p : reply->processes)
    if (app.empty() || p.application == app)
      table.rows.push_back({reply->host, reply->node,
                            node_ops::process_label(p.application, p.component), p.application,
                            p.component, p.figures});
}

void add_domain(Table &table, Pending &pending) {
  auto reply = control::reply_of<domain_ops::Top>(pending.get());
  if (!reply) {
    table.unreachable.push_back({"domain", reply.error().message, false});
    return;
  }
  table.rows.push_back({reply->host, "domain", "rsca-domaind", "", "", reply->daemon});
}

Json json_of(const Table &table) {
  Json processes = Json::array();
  for (const auto &r : table.rows) {
    Json row = protocol::encode(r.figures);
    row["host"] = r.host;
    row["node"] = r.node;
    row["what"] = r.what;
    if (!r.application.empty()) {
      row["application"] = r.application;
      row["component"] = r.component;
    }
    processes.push_back(std::move(row));
  }
  Json unreachable = Json::array();
  for (const auto &u : table.unreachable)
    unreachable.push_back({{"node", u.node}, {"error", u.error}, {"lost", u.lost}});
  return {{"processes", std::move(processes)}, {"unreachable", std::move(unreachable)}};
}

// Resident memory as top(1) shows it: MiB, one decimal.
std::string mib(std::uint64_t bytes) {
  return fmt::format("{:.1f}M", static_cast<double>(bytes) / (1024.0 * 1024.0));
}

void print_table(const Table &table) {
  fmt::print("{:<28} {:<36} {:>8} {:>7} {:>10} {:>7}\n", "HOST/NODE", "WHAT", "PID", "CPU%", "RSS",
             "THREADS");
  for (const auto &r : table.rows)
    fmt::print("{:<28} {:<36} {:>8} {:>7.1f} {:>10} {:>7}\n", fmt::format("{}/{}", r.host, r.node),
               r.what, r.figures.pid, r.figures.cpu_percent, mib(r.figures.rss_bytes),
               r.figures.threads);
  for (const auto &u : table.unreachable)
    fmt::print("{:<28} unreachable: {}\n", u.node, u.error);
}

int top(const std::string &app, const GlobalOptions &global) {
  auto client = DomainClient::connect(global);
  if (!client) {
    fmt::print(stderr, "rsca top: {}\n", client.error().to_string());
    return kFailed;
  }
  const std::chrono::milliseconds timeout(global.timeout_ms);
  if (!app.empty())
    if (auto shown = client->call<protocol::application::Show>({app}, timeout); !shown)
      return report_failure(global, "top", shown.error());
  auto nodes = client->call<domain_ops::Nodes>({}, timeout);
  if (!nodes)
    return report_failure(global, "top", nodes.error());
  // Every call is made before any is waited for: the slowest node sets the time, not their sum.
  std::optional<Pending> domain;
  if (app.empty())
    domain = client->call_async<domain_ops::Top>({}, timeout);
  std::vector<Pending> pending;
  for (const auto &n : nodes->nodes)
    pending.push_back(client->call_async_at<node_ops::Top>(n.address, {}, timeout));
  Table table;
  if (domain)
    add_domain(table, *domain);
  for (std::size_t i = 0; i < pending.size(); ++i)
    add_node(table, nodes->nodes[i].name, pending[i], app);
  for (const auto &n : nodes->lost)
    table.unreachable.push_back(
        {n.name, "lost: its DDS lease ran out; the domain keeps it until it is back", true});
  if (global.json)
    print_json(json_of(table));
  else
    print_table(table);
  return kOk;
}

} // namespace

void add_top_command(CLI::App &app, const GlobalOptions &global, int &exit_code) {
  auto *cmd = app.add_subcommand(
      "top", "CPU %, resident memory and threads of the daemons and of each component process, "
             "from every node [APP: only its processes]");
  auto of_app = std::make_shared<std::string>();
  cmd->add_option("app", *of_app, "only this running application's processes");
  cmd->callback([of_app, &global, &exit_code] { exit_code = top(*of_app, global); });
}

} // namespace rsca::cli
