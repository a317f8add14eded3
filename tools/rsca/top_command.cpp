// rsca top [APP] [-w [--interval 1s] [-n K]]: CPU, resident memory and threads of the daemons and
// of every process the nodes run, each node asked for its own (node.top) and the domain daemon for
// itself (domain.top), all at once. A node that does not answer is listed as unreachable; the
// others are shown all the same. So is a node the domain has lost (its DDS lease ran out): it is
// not asked, and not left out either, since its devices and components are still the domain's.
#include <unistd.h>

#include <cstdio>
#include <future>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "commands.hpp"
#include "common/units.hpp"
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

// How rsca top runs: once, or again every `interval` (-w) until interrupted or `iterations` (-n)
// tables were printed.
struct TopOptions {
  std::string app;
  bool watch = false;
  std::string interval = "1s";
  int iterations = 0; // 0: until interrupted (one without -w)
};

// One table: every node asked at once. An error is an exit code.
tl::expected<Table, int> gather(DomainClient &client, const std::string &app,
                                const GlobalOptions &global) {
  const std::chrono::milliseconds timeout(global.timeout_ms);
  if (!app.empty())
    if (auto shown = client.call<protocol::application::Show>({app}, timeout); !shown)
      return tl::unexpected(report_failure(global, "top", shown.error()));
  auto nodes = client.call<domain_ops::Nodes>({}, timeout);
  if (!nodes)
    return tl::unexpected(report_failure(global, "top", nodes.error()));
  // Every call is made before any is waited for: the slowest node sets the time, not their sum.
  std::optional<Pending> domain;
  if (app.empty())
    domain = client.call_async<domain_ops::Top>({}, timeout);
  std::vector<Pending> pending;
  for (const auto &n : nodes->nodes)
    pending.push_back(client.call_async_at<node_ops::Top>(n.address, {}, timeout));
  Table table;
  if (domain)
    add_domain(table, *domain);
  for (std::size_t i = 0; i < pending.size(); ++i)
    add_node(table, nodes->nodes[i].name, pending[i], app);
  for (const auto &n : nodes->lost)
    table.unreachable.push_back(
        {n.name, "lost: its DDS lease ran out; the domain keeps it until it is back", true});
  return table;
}

// Watching: --json prints one object a line; a terminal is cleared and redrawn; anything else
// (a pipe, a file) gets one table after the other, a blank line between.
void show(const Table &table, const TopOptions &options, const GlobalOptions &global) {
  if (global.json && options.watch)
    fmt::print("{}\n", json_of(table).dump());
  else if (global.json)
    print_json(json_of(table));
  else {
    if (options.watch && isatty(STDOUT_FILENO))
      fmt::print("\x1b[H\x1b[2J");
    print_table(table);
    if (options.watch && !isatty(STDOUT_FILENO))
      fmt::print("\n");
  }
  std::fflush(stdout); // a follower reads table by table
}

int top(const TopOptions &options, const GlobalOptions &global) {
  auto interval = parse_duration(options.interval);
  if (!interval || interval->infinite() || interval->value->count() <= 0) {
    fmt::print(stderr, "rsca top: --interval {}: give a duration such as 1s or 500ms\n",
               options.interval);
    return kUsage;
  }
  auto client = DomainClient::connect(global);
  if (!client) {
    return fail(global, "top", kFailed, client.error().to_string());
  }
  const int iterations = options.iterations > 0 ? options.iterations : (options.watch ? 0 : 1);
  for (int done = 0; iterations == 0 || done < iterations; ++done) {
    if (done > 0)
      std::this_thread::sleep_for(*interval->value); // the pace the user asked for
    auto table = gather(*client, options.app, global);
    if (!table)
      return table.error();
    show(*table, options, global);
  }
  return kOk;
}

} // namespace

void add_top_command(CLI::App &app, const GlobalOptions &global, int &exit_code) {
  auto *cmd = app.add_subcommand(
      "top", "CPU %, resident memory and threads of the daemons and of each component process, "
             "from every node [APP: only its processes]");
  auto options = std::make_shared<TopOptions>();
  cmd->add_option("app", options->app, "only this running application's processes");
  cmd->add_flag("-w,--watch", options->watch,
                "Refresh every --interval until interrupted (a terminal is redrawn; otherwise one "
                "table per interval, with --json one object per line)");
  cmd->add_option("--interval", options->interval, "The pace of -w (default 1s)");
  cmd->add_option("-n,--iterations", options->iterations,
                  "Stop after this many tables (implies -w)")
      ->check(CLI::PositiveNumber);
  cmd->callback([options, &global, &exit_code] {
    if (options->iterations > 0)
      options->watch = true;
    exit_code = top(*options, global);
  });
}

} // namespace rsca::cli
