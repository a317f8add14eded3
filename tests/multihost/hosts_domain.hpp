// A domain across network hosts (net_hosts.hpp): the domain daemon on host 1, node daemon i on
// host i + 1, every daemon on its host's network interface, on a DDS domain id and discovery tag
// of the test's own. The CLI runs on a host of the test's choice, through a node's control
// socket (a file: it reaches across namespaces, as a CLI on the node's own host would) or over
// DDS from that host. Daemons are stopped gracefully when it goes, then the hosts are removed
// with whatever still runs in them.
#pragma once

#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "../integration/child_process.hpp"
#include "../integration/wait_for.hpp"
#include "../unit/test_domain.hpp"
#include "net_hosts.hpp"

namespace rsca::test {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Json = nlohmann::json;

inline const fs::path kBin = RSCA_BIN_DIR;
inline const fs::path kSource = RSCA_SOURCE_DIR;

// What a CLI command did: its exit code, standard output and standard error.
struct CliRun {
  int rc = -1;
  std::string out, err;
  Json json() const { return Json::parse(out, nullptr, false); }
};

// What a test changes of the daemons it gets.
struct HostsOptions {
  // Node index → the size of a tmpfs (as mount's size=, "8m") its package cache is on: mounted in
  // the node's own mount namespace (ip netns exec makes one), gone with it.
  std::map<int, std::string> cache_tmpfs;
  // More arguments of rsca-domaind, e.g. {"--delivery", "as-is"}: the build's files as they are,
  // debug information and all, for a test that needs files larger than a tmpfs or a transfer.
  std::vector<std::string> domaind_args;
};

class HostsDomain {
public:
  explicit HostsDomain(int nodes, HostsOptions options = {}) : hosts_(nodes + 1) {
#ifdef RSCA_SANITIZE
    // 140 MB ASan executables stripped and compressed took the launch past the CLI's bounds: the
    // build's files as they are there (the file manager's unit tests cover the strip).
    if (options.domaind_args.empty())
      options.domaind_args = {"--delivery", "as-is"};
#endif
    fs::create_directories(run_ / "logs");
    env_ = {{"RSCA_DDS_DOMAIN", std::to_string(isolated_domain_id())},
            {"RSCA_DDS_TAG", isolated_tag()},
            {"RSCA_DDS_INTERFACE", hosts_.interface(1)},
            {"RSCA_RUN_DIR", run_.path.string()}};
    std::vector<std::string> domaind_args{
        "--dmd", (kSource / "profiles/dom/domain/DomainManager.dmd.xml").string(), "--repository",
        (run_ / "repository").string()};
    domaind_args.insert(domaind_args.end(), options.domaind_args.begin(),
                        options.domaind_args.end());
    domaind_ = start(1, "rsca-domaind", domaind_args);
    for (int i = 1; i <= nodes; ++i)
      nodes_.push_back(start_node(i, options));
    // Known to the domain once it lists them all, asked over DDS from the domain's host.
    REQUIRE(wait_for([&] {
      const auto listed = cli(1, {"--timeout-ms", "1000", "ls", "nodes"}, over_dds());
      return listed.rc == 0 && listed.json().at("nodes").size() == static_cast<std::size_t>(nodes);
    }));
  }

  ~HostsDomain() {
    for (auto &node : nodes_)
      if (node) {
        node->signal(SIGTERM);
        node->wait_exit(5s);
      }
    domaind_->signal(SIGTERM);
    domaind_->wait_exit(5s);
  }

  const NetHosts &hosts() const {
    return hosts_;
  }
  // The host node `index` (from 1) runs on.
  static int host_of_node(int index) {
    return index + 1;
  }

  // The CLI's environment to use DDS from its host rather than a node's socket.
  static ChildProcess::Environment over_dds() {
    return {{"RSCA_NODE_SOCKET", "none"}};
  }

  // Runs `rsca --json args...` on host `host`, with `more` of the environment.
  CliRun cli(int host, const std::vector<std::string> &args,
             const ChildProcess::Environment &more = {}) {
    const auto out = run_ / fmt::format("cli-{}.out", ++cli_runs_);
    const auto err = run_ / fmt::format("cli-{}.err", cli_runs_);
    std::vector<std::string> argv{
        "-c", "exec \"$0\" \"$@\" > " + out.string() + " 2> " + err.string(), ip_program()};
    auto on_host = hosts_.on_host(host, (kBin / "rsca").string(), {"--json"});
    on_host.insert(on_host.end(), args.begin(), args.end());
    argv.insert(argv.end(), on_host.begin(), on_host.end());
    auto env = env_;
    env.insert(env.end(), more.begin(), more.end());
    ChildProcess process("/bin/sh", argv, env);
    const auto status = process.wait_exit(60s);
    CliRun run;
    if (status && WIFEXITED(*status))
      run.rc = WEXITSTATUS(*status);
    run.out = read_file(out);
    run.err = read_file(err);
    return run;
  }

  template <typename Predicate>
  static bool wait_for(Predicate done, std::chrono::milliseconds limit = 20s) {
    return wait_until(done, limit, 50ms);
  }

  pid_t node_pid(int index) const {
    return nodes_.at(index - 1)->pid();
  }
  // Where node `index` keeps its package cache (inside its own mount namespace when on a tmpfs).
  fs::path cache_dir(int index) const {
    return run_ / fmt::format("cache-node{}", index);
  }
  const fs::path &run_dir() const {
    return run_.path;
  }

  // Kills the domain daemon as a crash would.
  void kill_domaind() {
    domaind_->signal(SIGKILL);
    domaind_->wait_exit(5s);
  }

private:
  std::unique_ptr<ChildProcess> start_node(int i, const HostsOptions &options) {
    const fs::path cache = cache_dir(i);
    fs::create_directories(cache);
    std::vector<std::string> args{
        "--dcd",
        (kSource / fmt::format("profiles/dev/nodes/node{}/DeviceManager.dcd.xml", i)).string(),
        "--control-socket",
        (run_ / fmt::format("node{}.sock", i)).string(),
        "--log-dir",
        (run_ / "logs").string(),
        "--cache-dir",
        cache.string()};
    auto tmpfs = options.cache_tmpfs.find(i);
    if (tmpfs == options.cache_tmpfs.end())
      return start(i + 1, "rsca-noded", args);
    // sh mounts the tmpfs in the namespace ip netns exec made, then becomes the node.
    std::vector<std::string> sh{
        "-c",
        "size=$1 dir=$2; shift 2; mount -t tmpfs -o size=$size tmpfs \"$dir\" && exec \"$@\"",
        "sh",
        tmpfs->second,
        cache.string(),
        (kBin / "rsca-noded").string()};
    sh.insert(sh.end(), args.begin(), args.end());
    return std::make_unique<ChildProcess>(ip_program(), hosts_.on_host(i + 1, "/bin/sh", sh), env_);
  }

  std::unique_ptr<ChildProcess> start(int host, const std::string &program,
                                      const std::vector<std::string> &args) {
    return std::make_unique<ChildProcess>(
        ip_program(), hosts_.on_host(host, (kBin / program).string(), args), env_);
  }

  static std::string read_file(const fs::path &path) {
    std::ifstream in(path);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }

  // The run folder (node sockets, logs, the repository), removed when it goes, also when the
  // constructor fails.
  struct RunFolder {
    fs::path path =
        fs::temp_directory_path() / fmt::format("rsca-mh-{}-{}", getpid(), std::random_device{}());
    ~RunFolder() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
    operator const fs::path &() const { return path; }
    fs::path operator/(const std::string &name) const { return path / name; }
  };

  RunFolder run_; // before the hosts: removed after every process in them is gone
  NetHosts hosts_;
  ChildProcess::Environment env_;
  std::unique_ptr<ChildProcess> domaind_;
  std::vector<std::unique_ptr<ChildProcess>> nodes_;
  int cli_runs_ = 0;
};

} // namespace rsca::test
