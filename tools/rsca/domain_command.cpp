// rsca domain up|down: a local domain daemon and N node daemons in the background, with their
// logs and pid files in a run folder.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include <fmt/format.h>

#include "commands.hpp"
#include "common/install_layout.hpp"
#include "common/own_folder.hpp"
#include "control/name_holder.hpp"
#include "domain_client.hpp"
#include "exit_codes.hpp"
#include "process/spawn.hpp"
#include "protocol/domain_announcement.hpp"
#include "protocol/domain_ops.hpp"

namespace rsca::cli {
namespace {

namespace fs = std::filesystem;
using control::Json;
using namespace std::chrono_literals;

// sockaddr_un's sun_path holds 108 bytes, the terminating zero included.
constexpr std::size_t kMaxSocketPath = 108;

fs::path default_sdrroot(const GlobalOptions &global) {
  if (!global.sdrroot.empty())
    return fs::absolute(global.sdrroot);
  if (const char *dir = std::getenv("RSCA_SDRROOT"); dir != nullptr && *dir != '\0')
    return dir;
  return layout::default_sdrroot();
}

bool alive(pid_t pid) {
  return pid > 0 && ::kill(pid, 0) == 0;
}

// Whether a daemon this command started has exited. Reaped here: an exited child stays a zombie,
// which kill(pid, 0) takes for alive (a refused domain daemon went unseen until the deadline).
bool has_exited(pid_t pid) {
  int status = 0;
  return ::waitpid(pid, &status, WNOHANG) == pid || !alive(pid);
}

std::optional<pid_t> read_pid(const fs::path &file) {
  std::ifstream in(file);
  pid_t pid = 0;
  if (in >> pid)
    return pid;
  return std::nullopt;
}

// Starts a daemon in its own session (so the terminal's Ctrl-C does not reach it), with stdout
// and stderr in `log`, and records its pid in `pid_file`. It outlives this command: nobody here
// reaps it.
Expected<pid_t> spawn_daemon(const fs::path &program, const std::vector<std::string> &args,
                             const fs::path &log, const fs::path &pid_file) {
  auto daemon =
      process::spawn({.program = program, .args = args, .log_file = log}, process::Group::Session);
  if (!daemon)
    return tl::unexpected(std::move(daemon.error()));
  std::ofstream(pid_file) << daemon->pid << '\n';
  return daemon->pid;
}

// Waits for a process to exit, without polling by sleeping: a pidfd becomes readable at exit.
bool wait_exit(pid_t pid, std::chrono::milliseconds timeout) {
  const auto pidfd = process::open_pidfd(pid);
  if (!pidfd)
    return !alive(pid);
  return process::wait_exited(pidfd, timeout) || !alive(pid);
}

std::string tail(const fs::path &log, std::size_t lines = 8) {
  std::ifstream in(log);
  std::vector<std::string> all;
  for (std::string line; std::getline(in, line);)
    all.push_back(line);
  std::string out;
  for (std::size_t i = all.size() > lines ? all.size() - lines : 0; i < all.size(); ++i)
    out += "    " + all[i] + "\n";
  return out;
}

// The DCD of node i: the SDR root's own nodeI if it has one, else one made in the run folder
// from node1's, in an SDR root that links the real devices.
Expected<fs::path> node_dcd(int i, const fs::path &sdrroot, const fs::path &run) {
  const fs::path own = sdrroot / fmt::format("dev/nodes/node{}/DeviceManager.dcd.xml", i);
  if (fs::is_regular_file(own))
    return own;
  const fs::path templ = sdrroot / "dev/nodes/node1/DeviceManager.dcd.xml";
  if (!fs::is_regular_file(templ))
    return make_error({templ.string(), 0, 0}, "missing-file",
                      "no node DCD to make more nodes from");
  const fs::path sdr = run / "sdr";
  std::error_code ec;
  fs::create_directories(sdr / "dev/nodes", ec);
  for (const char *shared : {"dev/devices", "dev/mgr"})
    if (!fs::exists(sdr / shared))
      fs::create_directory_symlink(sdrroot / shared, sdr / shared, ec);
  std::ifstream in(templ);
  std::stringstream text;
  text << in.rdbuf();
  std::string dcd = text.str();
  const std::string from = "node1", to = fmt::format("node{}", i);
  for (auto at = dcd.find(from); at != std::string::npos; at = dcd.find(from, at + to.size()))
    dcd.replace(at, from.size(), to);
  const fs::path out = sdr / fmt::format("dev/nodes/node{}/DeviceManager.dcd.xml", i);
  fs::create_directories(out.parent_path(), ec);
  std::ofstream(out) << dcd;
  return out;
}

// One node daemon in the background for `dcd`, its log and pid file named `name`.
Expected<pid_t> spawn_node(const fs::path &dcd, const std::string &name, const fs::path &run,
                           const GlobalOptions &global) {
  const fs::path bin = own_folder();
  std::vector<std::string> args{"--dcd",       dcd.string(), "--domain",
                                global.domain, "--log-dir",  (run / "logs").string()};
  // The CLI reaches the domain through the node's socket; a path too long for one leaves the
  // CLI on DDS.
  if (const fs::path socket = run / (name + ".sock"); socket.string().size() < kMaxSocketPath) {
    args.push_back("--control-socket");
    args.push_back(socket.string());
  }
  return spawn_daemon(bin / "rsca-noded", args, run / (name + ".log"), run / (name + ".pid"));
}

// Who serves domain `domain` on this DDS domain and tag already, if a live daemon does
// (control/name_holder.hpp): a second one beside it would take its requests, and its nodes named
// as the first's would take theirs over.
std::optional<std::string> domain_held(const std::string &domain) {
  auto settings = dds::DdsSettings::from_environment();
  settings.trace = "none";
  auto participant = dds::Participant::create(settings);
  if (!participant)
    return std::nullopt; // the domain daemon, joining the same way, will say why
  return control::live_holder<protocol::domain::DomainAnnouncement>(
      **participant, protocol::domain_address(domain), fmt::format("domain {}", domain),
      "rsca-domaind");
}

// Stops a daemon as `domain down` does: asked, then killed if it does not go within 5 s.
void stop_daemon(pid_t pid) {
  ::kill(pid, SIGTERM);
  if (!wait_exit(pid, 5s)) {
    ::kill(pid, SIGKILL);
    wait_exit(pid, 2s);
  }
}

struct Started {
  pid_t pid;
  fs::path log;
  fs::path pid_file;
};

// Every daemon an `up` started, stopped, nodes first, and their pid files: an `up` that fails
// leaves nothing of its own running. `rc`, for the caller to return.
int stop_started(const std::vector<Started> &started, int rc) {
  std::error_code ec;
  for (auto it = started.rbegin(); it != started.rend(); ++it) {
    if (!has_exited(it->pid))
      stop_daemon(it->pid);
    fs::remove(it->pid_file, ec);
  }
  return rc;
}

// A daemon `up` started stopped: every other one it started goes too.
int abandon_up(const std::vector<Started> &started, const Started &stopped,
               const GlobalOptions &global) {
  return stop_started(
      started, fail(global, "domain up", kFailed,
                    fmt::format("a daemon (pid {}) stopped; the {} other daemon(s) it started are "
                                "stopped; its log ends:\n{}",
                                stopped.pid, started.size() - 1, tail(stopped.log))));
}

// Whether every node daemon of `started` from `first_node` on is registered: a domain that lists
// nodes of the same names run by others is not this one.
bool all_registered(const protocol::domain::NodesReply &reply, const std::vector<Started> &started,
                    std::size_t first_node) {
  std::set<std::int64_t> listed;
  for (const auto &n : reply.nodes)
    listed.insert(n.pid);
  return std::all_of(started.begin() + static_cast<std::ptrdiff_t>(first_node), started.end(),
                     [&](const Started &s) { return listed.contains(s.pid); });
}

// Waits until the node daemons of `started` (from `first_node` on) are registered; one of
// `started` that stops meanwhile makes the others stop too. kOk with the domain's nodes in `reply`.
int wait_registered(const std::vector<Started> &started, std::size_t first_node,
                    const fs::path &run, const GlobalOptions &global,
                    protocol::domain::NodesReply &reply) {
  auto client = DomainClient::connect(global);
  if (!client)
    return fail(global, "domain up", kFailed, client.error().to_string());
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::milliseconds(global.timeout_ms) * 4;
  for (;;) {
    for (const auto &s : started)
      if (has_exited(s.pid))
        return abandon_up(started, s, global);
    auto listed = client->call<protocol::domain::Nodes>({}, 1s);
    if (listed && all_registered(*listed, started, first_node)) {
      reply = *listed;
      return kOk;
    }
    if (std::chrono::steady_clock::now() > deadline)
      return fail(global, "domain up", kUnreachable,
                  fmt::format("the nodes did not all register in time (see {})", run.string()));
    std::this_thread::sleep_for(50ms); // pacing a poll of the domain, not a wait for a condition
  }
}

// Node daemon `name` for `dcd`, appended to `started`; kOk, or kFailed after saying why.
int start_node(const fs::path &dcd, const std::string &name, const fs::path &run,
               const GlobalOptions &global, std::vector<Started> &started) {
  auto pid = spawn_node(dcd, name, run, global);
  if (!pid)
    return fail(global, "domain up", kFailed, pid.error().to_string());
  started.push_back({*pid, run / (name + ".log"), run / (name + ".pid")});
  return kOk;
}

// One node daemon per DCD given with --node, named after its DCD's folder, appended to `started`.
int spawn_extra_nodes(const std::vector<std::string> &dcds, const fs::path &run,
                      const GlobalOptions &global, std::vector<Started> &started) {
  for (const auto &dcd : dcds) {
    const std::string name = fs::path(dcd).parent_path().filename().string();
    if (auto pid = read_pid(run / (name + ".pid")); pid && alive(*pid))
      return fail(global, "domain up", kRejected,
                  fmt::format("a node {} is already up in {} (pid {})", name, run.string(), *pid));
    if (int rc = start_node(fs::absolute(dcd), name, run, global, started); rc != kOk)
      return rc;
  }
  return kOk;
}

void print_up(const protocol::domain::NodesReply &reply, const fs::path &run,
              const GlobalOptions &global, const std::string &text) {
  if (global.json) {
    Json shown = protocol::encode(reply);
    shown["run_dir"] = run.string();
    print_json(shown);
  } else {
    fmt::print("{}; logs in {}\n", text, run.string());
  }
}

// `rsca domain up --node DCD` beside a domain already up in `run`: only those nodes start, and
// join it; what fails stops them again, and the domain keeps running.
int add_nodes(const std::vector<std::string> &dcds, const fs::path &run,
              const GlobalOptions &global) {
  std::vector<Started> started;
  if (int rc = spawn_extra_nodes(dcds, run, global, started); rc != kOk)
    return stop_started(started, rc);
  protocol::domain::NodesReply reply;
  if (int rc = wait_registered(started, 0, run, global, reply); rc != kOk)
    return stop_started(started, rc);
  print_up(reply, run, global,
           fmt::format("domain {}: {} node(s) added, {} in all", global.domain, started.size(),
                       reply.nodes.size()));
  return kOk;
}

int up(int nodes, bool nodes_given, const std::vector<std::string> &extra_dcds, const fs::path &run,
       const GlobalOptions &global) {
  std::error_code ec;
  fs::create_directories(run / "logs", ec);
  if (auto pid = read_pid(run / "domaind.pid"); pid && alive(*pid)) {
    if (!extra_dcds.empty() && !nodes_given)
      return add_nodes(extra_dcds, run, global);
    return fail(global, "domain up", kRejected,
                fmt::format("a domain is already up in {} (domaind pid {}); `rsca domain down` "
                            "first, or `rsca domain up --node DCD` to add a node to it",
                            run.string(), *pid));
  }
  if (auto held = domain_held(global.domain))
    return fail(global, "domain up", kRejected,
                fmt::format("{}; nothing started (stop that domain first, or use another DDS "
                            "domain or tag: RSCA_DDS_DOMAIN, RSCA_DDS_TAG)",
                            *held));
  const fs::path bin = own_folder();
  const fs::path sdrroot = default_sdrroot(global);
  auto domaind = spawn_daemon(bin / "rsca-domaind",
                              {"--dmd", (sdrroot / "dom/domain/DomainManager.dmd.xml").string(),
                               "--repository", (run / "repository").string()},
                              run / "domaind.log", run / "domaind.pid");
  if (!domaind)
    return fail(global, "domain up", kFailed, domaind.error().to_string());
  std::vector<Started> started{{*domaind, run / "domaind.log", run / "domaind.pid"}};
  for (int i = 1; i <= nodes; ++i) {
    auto dcd = node_dcd(i, sdrroot, run);
    if (!dcd)
      return stop_started(started, fail(global, "domain up", kFailed, dcd.error().to_string()));
    if (int rc = start_node(*dcd, fmt::format("node{}", i), run, global, started); rc != kOk)
      return stop_started(started, rc);
  }
  if (int rc = spawn_extra_nodes(extra_dcds, run, global, started); rc != kOk)
    return stop_started(started, rc);
  protocol::domain::NodesReply reply;
  if (int rc = wait_registered(started, 1, run, global, reply); rc != kOk)
    return stop_started(started, rc);
  print_up(reply, run, global,
           fmt::format("domain {} up: domaind pid {}, {} node(s)", global.domain, *domaind,
                       started.size() - 1));
  return kOk;
}

int down(const fs::path &run, const GlobalOptions &global) {
  // A folder that is not there (a typo, or RSCA_DDS_TAG or RSCA_DDS_DOMAIN changed since `up`,
  // which moves the default) is said, not thrown: it was an uncaught filesystem_error, rc 134.
  std::error_code ec;
  fs::directory_iterator entries(run, fs::directory_options::skip_permission_denied, ec);
  if (ec) {
    const std::string why =
        fmt::format("no domain was started in {}: {} (`rsca domain up` keeps its pid files in "
                    "--run-dir, by default $RSCA_RUN_DIR, else a folder per user, DDS domain id "
                    "and RSCA_DDS_TAG: {})",
                    run.string(), ec.message(), default_run_dir().string());
    return report_failure(global, "domain down",
                          control::CallError{control::Status::NotFound, why});
  }
  std::vector<fs::path> pid_files;
  for (const auto &e : entries)
    if (e.path().extension() == ".pid" && e.path().filename() != "domaind.pid")
      pid_files.push_back(e.path());
  pid_files.push_back(run / "domaind.pid"); // nodes first: they stop their components
  int stopped = 0;
  for (const auto &file : pid_files) {
    auto pid = read_pid(file);
    if (pid && alive(*pid)) {
      stop_daemon(*pid);
      ++stopped;
    }
    fs::remove(file, ec);
  }
  if (global.json)
    print_json({{"stopped", stopped}, {"run_dir", run.string()}});
  else
    fmt::print("domain down: {} daemon(s) stopped\n", stopped);
  return kOk;
}

} // namespace

void add_domain_command(CLI::App &app, const GlobalOptions &global, int &exit_code) {
  auto *domain =
      app.add_subcommand("domain", "Start or stop a local domain (daemons in the background)");
  domain->require_subcommand(1);
  auto run = std::make_shared<std::string>(default_run_dir().string());
  auto nodes = std::make_shared<int>(2);
  auto *up_cmd = domain->add_subcommand(
      "up", "Start a domain daemon and N node daemons; return when all are registered");
  auto *nodes_option = up_cmd->add_option("--nodes", *nodes, "How many node daemons")
                           ->capture_default_str()
                           ->check(CLI::Range(1, 100));
  auto extra = std::make_shared<std::vector<std::string>>();
  up_cmd
      ->add_option("--node", *extra,
                   "One more node daemon, for this DCD (repeatable); with a domain already up "
                   "in the run folder (and no --nodes), only these start and join it")
      ->check(CLI::ExistingFile);
  up_cmd->add_option("--run-dir", *run, "Logs and pid files go here")->capture_default_str();
  up_cmd->callback([=, &global, &exit_code] {
    exit_code = up(*nodes, nodes_option->count() > 0, *extra, *run, global);
  });
  auto *down_cmd = domain->add_subcommand("down", "Stop the daemons started by `rsca domain up`");
  down_cmd->add_option("--run-dir", *run, "Where `domain up` put its pid files")
      ->capture_default_str();
  down_cmd->callback([=, &global, &exit_code] { exit_code = down(*run, global); });
}

} // namespace rsca::cli
