// rsca logs APP[/COMP]|NODE [-n LINES] [--since T] [-f]: the logs of an application's component
// processes, read by the nodes that run them (node.logs), so they come from any host, or a node
// daemon's own log, read by that node (node.daemon_logs). The domain says where each component
// runs (app.show) and where each node is (domain.nodes); each node is asked for the components it
// runs. -f follows: the nodes are asked again every half second from where their last reply
// ended. --failed reads the logs of the processes of a failed launch the domain remembers
// (app.failed) the same way, from the files their rollback left on the nodes, each from where
// that launch's process began writing it. A name that is both an application's and a node's is
// the application's (the one a user launched and is more likely to mean); `node:NAME` names the
// node.
#include <algorithm>
#include <chrono>
#include <ctime>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "commands.hpp"
#include "domain_client.hpp"
#include "durations.hpp"
#include "exit_codes.hpp"
#include "protocol/application_ops.hpp"
#include "protocol/domain_ops.hpp"
#include "protocol/node_ops.hpp"

namespace rsca::cli {
namespace {

namespace app_ops = protocol::application;
namespace domain_ops = protocol::domain;
namespace node_ops = protocol::node;
using control::Json;

struct LogsOptions {
  std::string target; // APP, APP/COMP, NODE or node:NODE
  std::size_t lines = 100;
  std::string since; // a duration ("300s"): only the lines logged since then
  bool follow = false;
  bool failed = false; // the logs of the last failed launch (of APP when given)
};

constexpr std::chrono::milliseconds kFollowPace{500};

constexpr std::string_view kNodePrefix = "node:";

// One log, and where reading it goes on: a component's, or a node daemon's own.
struct Source {
  std::string node_address;
  std::string node; // a node daemon's own log: its node's name; empty: a component's log
  // A component's; its offset and max_bytes are where and how much to read a daemon's log too.
  node_ops::LogsRequest request;
  bool keeping = false; // --since: whether the last line read was kept
  const std::string &label() const { return node.empty() ? request.component : node; }
};

// A component's log lines start with the component runtime's local time, "[YYYY-MM-DD
// HH:MM:SS.mmm]", as a node daemon's do (node/daemon_log.hpp), which orders them as text: --since
// compares that with the time it names. A line without it (a program's own output) goes with the
// line before it.
std::string local_stamp(std::chrono::system_clock::time_point at) {
  const std::time_t t = std::chrono::system_clock::to_time_t(at);
  std::tm local{};
  localtime_r(&t, &local);
  return fmt::format("{:04}-{:02}-{:02} {:02}:{:02}:{:02}", local.tm_year + 1900, local.tm_mon + 1,
                     local.tm_mday, local.tm_hour, local.tm_min, local.tm_sec);
}

constexpr std::size_t kStampLength = 19; // YYYY-MM-DD HH:MM:SS

std::vector<std::string> since(std::vector<std::string> lines, const std::string &stamp,
                               bool &keeping) {
  if (stamp.empty())
    return lines;
  std::vector<std::string> kept;
  for (auto &line : lines) {
    const bool stamped = line.size() > kStampLength && line[0] == '[' && line[5] == '-' &&
                         line[kStampLength - 2] == ':';
    if (stamped)
      keeping = line.compare(1, kStampLength, stamp) >= 0;
    if (keeping)
      kept.push_back(std::move(line));
  }
  return kept;
}

std::vector<std::string> lines_of(const std::string &text) {
  std::vector<std::string> lines;
  std::size_t at = 0;
  while (at < text.size()) {
    auto nl = text.find('\n', at);
    if (nl == std::string::npos)
      nl = text.size();
    lines.push_back(text.substr(at, nl - at));
    at = nl + 1;
  }
  return lines;
}

// The node named `name`'s own log; none (with rc) when the domain has no such node. `explicitly`:
// named as a node (node:NAME), not a name no application has.
std::vector<Source> node_source(const domain_ops::NodesReply &nodes, const std::string &name,
                                bool explicitly, const GlobalOptions &global, int &rc) {
  for (const auto &n : nodes.nodes)
    if (n.name == name)
      return {{n.address,
               n.name,
               {{}, {}, std::nullopt, std::nullopt, node_ops::LogsRequest::kMaxBytes}}};
  rc = report_failure(global, "logs",
                      {control::Status::NotFound,
                       explicitly ? fmt::format("no node {} in the domain", name)
                                  : fmt::format("no application or node {} in the domain", name)});
  return {};
}

// The components of the application shown (all, or `component`), each with its node's address.
std::vector<Source> component_sources(const app_ops::Show::Reply &shown,
                                      const domain_ops::NodesReply &nodes,
                                      const std::string &component) {
  std::vector<Source> sources;
  for (const auto &c : shown.components) {
    if (!component.empty() && c.id != component)
      continue;
    for (const auto &n : nodes.nodes)
      if (n.name == c.node)
        sources.push_back(
            {n.address,
             {},
             {shown.name, c.id, c.pid, std::nullopt, node_ops::LogsRequest::kMaxBytes}});
  }
  return sources;
}

// The logs of the processes of the last launch that failed (of the application the target names,
// and only its component COMP when APP/COMP), which the domain remembers (app.failed): their
// files stay on their nodes after the rollback. Printed first: which launch it was.
std::vector<Source> failed_sources(const DomainClient &client, const LogsOptions &options,
                                   const domain_ops::NodesReply &nodes, const GlobalOptions &global,
                                   int &rc) {
  const auto slash = options.target.find('/');
  const std::string app = options.target.substr(0, slash);
  const std::string component =
      slash == std::string::npos ? std::string() : options.target.substr(slash + 1);
  auto failed =
      client.call<app_ops::Failed>({app.empty() ? std::nullopt : std::optional<std::string>(app)},
                                   std::chrono::milliseconds(global.timeout_ms));
  if (!failed) {
    rc = report_failure(global, "logs", failed.error());
    return {};
  }
  if (failed->launches.empty()) {
    rc = report_failure(
        global, "logs",
        {control::Status::NotFound,
         fmt::format("no failed launch{} is remembered (the domain keeps the last {})",
                     app.empty() ? "" : " of " + app, app_ops::FailedLaunch::kKept)});
    return {};
  }
  const auto &last = failed->launches.back();
  std::vector<Source> sources;
  for (const auto &p : last.components) {
    const bool shared = std::any_of(sources.begin(), sources.end(),
                                    [&](const Source &s) { return s.request.component == p.log; });
    if (shared || (!component.empty() && p.component != component))
      continue; // a component host's log once; only COMP's
    for (const auto &n : nodes.nodes)
      if (n.name == p.node)
        sources.push_back({n.address,
                           {},
                           {last.application, p.log, std::nullopt, p.log_offset,
                            node_ops::LogsRequest::kMaxBytes}});
  }
  if (sources.empty())
    rc = report_failure(
        global, "logs",
        {control::Status::NotFound,
         fmt::format("the last failed launch of {} has no {} on a node", last.application,
                     component.empty() ? "process" : "component " + component)});
  else if (!global.json)
    fmt::print("launch {} of {} failed at step '{}' at {}; the logs of its processes:\n",
               last.launch_id, last.application, last.step,
               local_stamp(std::chrono::system_clock::time_point(
                   std::chrono::milliseconds(last.failed_at_ms))));
  return sources;
}

// The logs the target names, each with its node's address. rc: the exit code when it fails.
std::vector<Source> sources_of(const DomainClient &client, const LogsOptions &options,
                               const GlobalOptions &global, int &rc) {
  const std::chrono::milliseconds timeout(global.timeout_ms);
  auto nodes = client.call<domain_ops::Nodes>({}, timeout);
  if (!nodes) {
    rc = report_failure(global, "logs", nodes.error());
    return {};
  }
  if (options.failed)
    return failed_sources(client, options, *nodes, global, rc);
  if (options.target.rfind(kNodePrefix, 0) == 0)
    return node_source(*nodes, options.target.substr(kNodePrefix.size()), true, global, rc);
  const auto slash = options.target.find('/');
  const std::string app = options.target.substr(0, slash);
  const std::string component =
      slash == std::string::npos ? std::string() : options.target.substr(slash + 1);
  auto shown = client.call<app_ops::Show>({app}, timeout);
  if (!shown && shown.error().status == control::Status::NotFound && slash == std::string::npos)
    return node_source(*nodes, app, false, global, rc); // no application of that name: a node's
  if (!shown) {
    rc = report_failure(global, "logs", shown.error());
    return {};
  }
  auto sources = component_sources(*shown, *nodes, component);
  if (sources.empty())
    rc = report_failure(global, "logs",
                        {control::Status::NotFound,
                         component.empty()
                             ? fmt::format("no component of {} runs on a node", app)
                             : fmt::format("{} has no component {} on a node", app, component)});
  return sources;
}

// Prints a reply's lines (the last `keep` of them when not all), prefixed with the component when
// the logs of several are shown; in JSON, each names its node or its component.
void print_lines(const Source &source, const std::vector<std::string> &lines, std::size_t keep,
                 bool prefix, const GlobalOptions &global) {
  const std::size_t first = lines.size() > keep ? lines.size() - keep : 0;
  for (std::size_t i = first; i < lines.size(); ++i) {
    if (global.json)
      fmt::print("{}\n", (source.node.empty() ? Json{{"application", source.request.application},
                                                     {"component", source.request.component},
                                                     {"line", lines[i]}}
                                              : Json{{"node", source.node}, {"line", lines[i]}})
                             .dump());
    else if (prefix)
      fmt::print("{} | {}\n", source.request.component, lines[i]);
    else
      fmt::print("{}\n", lines[i]);
  }
  std::fflush(stdout);
}

// Asks the node of `source` for its next piece.
std::future<control::CallResult<Json>> ask(const DomainClient &client, const Source &source,
                                           std::chrono::milliseconds timeout) {
  if (source.node.empty())
    return client.call_async_at<node_ops::Logs>(source.node_address, source.request, timeout);
  return client.call_async_at<node_ops::DaemonLogs>(
      source.node_address, {source.request.offset, source.request.max_bytes}, timeout);
}

// Reads each source once, from where it stands; the exit code of the first failure.
int read_once(const DomainClient &client, std::vector<Source> &sources, std::size_t keep,
              const std::string &stamp, const GlobalOptions &global) {
  std::vector<std::future<control::CallResult<Json>>> pending;
  for (const auto &s : sources)
    pending.push_back(ask(client, s, std::chrono::milliseconds(global.timeout_ms)));
  int rc = kOk;
  for (std::size_t i = 0; i < sources.size(); ++i) {
    // node.logs's reply is node.daemon_logs's too.
    auto reply = control::reply_of<node_ops::Logs>(pending[i].get());
    if (!reply) {
      const int failed =
          report_failure(global, fmt::format("logs {}", sources[i].label()), reply.error());
      rc = rc == kOk ? failed : rc;
      continue;
    }
    sources[i].request.offset = reply->next;
    print_lines(sources[i], since(lines_of(reply->text), stamp, sources[i].keeping), keep,
                sources.size() > 1, global);
  }
  return rc;
}

int logs(const LogsOptions &options, const GlobalOptions &global) {
  auto client = DomainClient::connect(global);
  if (!client) {
    return fail(global, "logs", kFailed, client.error().to_string());
  }
  std::string stamp;
  if (!options.since.empty()) {
    auto ago = parse_cli_duration(options.since);
    if (!ago)
      return fail(global, "logs", kUsage, fmt::format("--since: {}", ago.error()));
    stamp = local_stamp(std::chrono::system_clock::now() -
                        std::chrono::duration_cast<std::chrono::system_clock::duration>(*ago));
  }
  int rc = kOk;
  auto sources = sources_of(*client, options, global, rc);
  if (sources.empty())
    return rc;
  rc = read_once(*client, sources, options.lines, stamp, global);
  if (!options.follow || options.failed) // a failed launch's processes log no more
    return rc;
  for (;;) { // until interrupted
    std::this_thread::sleep_for(kFollowPace);
    (void)read_once(*client, sources, SIZE_MAX, stamp, global);
  }
}

} // namespace

void add_logs_command(CLI::App &app, const GlobalOptions &global, int &exit_code) {
  auto *cmd = app.add_subcommand(
      "logs", "The logs of a running application's components (APP) or of one (APP/COMP), read "
              "by the nodes that run them, or a node daemon's own log (NODE); with --failed, "
              "those of the last failed launch's processes, kept after its rollback");
  auto options = std::make_shared<LogsOptions>();
  cmd->add_option("target", options->target,
                  "APP, APP/COMPONENT or NODE; a name that is both an application's and a "
                  "node's is the application's: node:NODE names the node. With --failed: "
                  "APP or APP/COMPONENT, or nothing (the last failed launch of any)");
  auto *lines = cmd->add_option("-n,--lines", options->lines,
                                "the last LINES lines of each log (with --failed: all it holds "
                                "of that launch, up to 1 MiB each, unless given)")
                    ->capture_default_str();
  cmd->add_flag("--failed", options->failed,
                "the logs of the processes of the last launch that failed (of APP when given), "
                "which its rollback ended: the domain remembers the last 16 failed launches, a "
                "node keeps the log files (docs/architecture.md)");
  cmd->add_option("--since", options->since,
                  "only the lines logged in the last T (a duration: 90s, 5m, 1h)");
  cmd->add_flag("-f,--follow", options->follow, "go on printing what is logged, until Ctrl-C");
  cmd->callback([options, lines, &global, &exit_code] {
    if (options->target.empty() && !options->failed) {
      fmt::print(stderr, "rsca logs: a target is required (APP, APP/COMP or NODE), or --failed\n");
      exit_code = kUsage;
      return;
    }
    if (options->failed && lines->count() == 0)
      options->lines = SIZE_MAX;
    exit_code = logs(*options, global);
  });
}

} // namespace rsca::cli
