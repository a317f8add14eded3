// The whole product with real processes, for integration tests: rsca-domaind and node daemons
// on loopback, on a DDS domain of their own, driven through the CLI and the control plane. A test
// checks that what it launched leaves nothing behind (require_clean).
#pragma once
#include <signal.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <thread>

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <future>

#include "../unit/test_domain.hpp"
#include "cache_seed.hpp"
#include "child_process.hpp"
#include "control/endpoint.hpp"
#include "wait_for.hpp"

namespace rsca::test {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using rsca::control::Json;
using rsca::control::Status;

inline const fs::path kBin = RSCA_BIN_DIR;
inline const fs::path kSource = RSCA_SOURCE_DIR;
inline const fs::path kTestSdr = kSource / "tests/data/integration";

// A file's bytes; empty when it cannot be read.
inline std::string read_file(const fs::path &file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline bool process_exists(long pid) {
  if (pid <= 0)
    return false;
  std::ifstream stat(fmt::format("/proc/{}/stat", pid));
  std::string state;
  if (!stat)
    return false;
  std::string skip;
  stat >> skip >> skip >> state;
  return state != "Z"; // a zombie has exited; its parent has not reaped it yet
}

// A domain daemon and `nodes` node daemons, stopped (nodes first, gracefully) when it goes.
// How long a call or a wait on the domain may take by default. Under the sanitizers every
// process of a launch runs several times slower (ASan executables of ~140 MB hashed, copied and
// started, two tests at once on two CPUs): a launch took 11-14 s there, past the 10 s that serve
// the optimised build.
#ifdef RSCA_SANITIZE
inline constexpr std::chrono::milliseconds kDomainWait{60000};
#else
inline constexpr std::chrono::milliseconds kDomainWait{10000};
#endif

// Under the sanitizers a component executable is about 140 MB (100 MB without its debug
// sections), and hashing, stripping and compressing two of them at every test's first launch took
// the launch past the tests' 10 s deadlines with two tests running at once: there the domain
// delivers the build's files as they are (rsca-domaind --delivery as-is), as it did before issue
// 37, unless a test of the delivery itself keeps the default by holding a DefaultDelivery.
inline bool default_delivery_kept = false;
struct DefaultDelivery {
  DefaultDelivery() { default_delivery_kept = true; }
  ~DefaultDelivery() { default_delivery_kept = false; }
  DefaultDelivery(const DefaultDelivery &) = delete;
  DefaultDelivery &operator=(const DefaultDelivery &) = delete;
};

// Under the sanitizers, node caches start warm (cache_seed.hpp) unless a test holds
// DefaultDelivery or ColdCaches: one whose node must fetch a file it could otherwise link from an
// earlier test's (a file the domain serves altered under its old hash).
inline bool cold_caches_kept = false;
struct ColdCaches {
  ColdCaches() { cold_caches_kept = true; }
  ~ColdCaches() { cold_caches_kept = false; }
  ColdCaches(const ColdCaches &) = delete;
  ColdCaches &operator=(const ColdCaches &) = delete;
};

class TestDomain {
public:
  // Twice the product's default: a dozen component processes under ASan on a loaded 2-core CI
  // host may take seconds to register. Tests of the timeout itself give their own.
  static constexpr int kRegistrationTimeoutMs = 20000;

  explicit TestDomain(int nodes = 2, int registration_timeout_ms = kRegistrationTimeoutMs)
      : TestDomain(shipped_nodes(nodes), registration_timeout_ms) {}

  // One node daemon per DCD; `more_env` adds to every daemon's environment (RSCA_DDS_LEASE_MS).
  explicit TestDomain(const std::vector<fs::path> &dcds,
                      int registration_timeout_ms = kRegistrationTimeoutMs,
                      const ChildProcess::Environment &more_env = {})
      : run_(fs::temp_directory_path() /
             fmt::format("rsca-it-{}-{}", getpid(), std::random_device{}())) {
    fs::create_directories(run_ / "logs");
    // The run folder is the CLI's too: it reaches the domain through the nodes' sockets there.
    env_ = {{"RSCA_DDS_DOMAIN", std::to_string(rsca::test::isolated_domain_id())},
            {"RSCA_DDS_TAG", rsca::test::isolated_tag()},
            {"RSCA_RUN_DIR", run_.string()}};
    env_.insert(env_.end(), more_env.begin(), more_env.end());
    start_domaind(registration_timeout_ms);
    for (const auto &dcd : dcds)
      launch_node(dcd);
    auto pp = rsca::test::participant();
    // Following announcements, the client learns which node serves each component's address.
    rsca::control::EndpointOptions options;
    options.on_announcement = [](const rsca::control::AnnouncementEvent &) {};
    auto endpoint =
        rsca::control::Endpoint::open(pp, fmt::format("rsca/cli/test-{}", getpid()), options);
    REQUIRE(endpoint.has_value());
    participant_ = pp;
    client_ = std::move(*endpoint);
    REQUIRE(wait_for([&] {
      auto r = call("domain.nodes");
      return r && r->at("nodes").size() == dcds.size();
    }));
  }

  // The project's own nodes: profiles/dev/nodes/node1..N.
  static std::vector<fs::path> shipped_nodes(int nodes) {
    std::vector<fs::path> dcds;
    for (int i = 1; i <= nodes; ++i)
      dcds.push_back(kSource / fmt::format("profiles/dev/nodes/node{}/DeviceManager.dcd.xml", i));
    return dcds;
  }

  ~TestDomain() {
    for (auto &n : nodes_)
      if (n) {
        n->signal(SIGTERM);
        n->wait_exit(5s);
      }
    if (domaind_) {
      domaind_->signal(SIGTERM);
      domaind_->wait_exit(5s);
    }
    std::error_code ec;
    if (seeded_)
      for (const auto &cache : fs::directory_iterator(run_ / "cache", ec))
        cache_seed::keep(kBin, cache.path());
    cache_seed::remove_tree(run_ / "cache");
    fs::remove_all(run_, ec);
  }

  rsca::control::CallResult<Json> call(const std::string &op, Json body = Json::object(),
                                       std::chrono::milliseconds timeout = kDomainWait) {
    return client_->call_sync("rsca/domain", op, std::move(body), timeout);
  }

  // Calls node `index` (from 1) of the project's shipped nodes.
  rsca::control::CallResult<Json> call_node(int index, const std::string &op,
                                            Json body = Json::object()) {
    return client_->call_sync(fmt::format("rsca/node/node{}", index), op, std::move(body), 5s);
  }

  // Launches a SAD the project ships (profiles/dom/waveforms/<app>/<app>.sad.xml) with the CLI;
  // the application as app.show gives it. `options`: more of the CLI's (`--strategy spread`).
  Json launch_shipped(const std::string &app, const std::vector<std::string> &options = {}) {
    std::vector<std::string> args{
        "launch", (kSource / fmt::format("profiles/dom/waveforms/{0}/{0}.sad.xml", app)).string()};
    args.insert(args.end(), options.begin(), options.end());
    auto [rc, out] = cli(args);
    INFO(out);
    REQUIRE(rc == 0);
    auto shown = call("app.show", Json{{"app", app}});
    REQUIRE(shown.has_value());
    return *shown;
  }

  // Runs the CLI against this domain, with `more` of the environment; returns its exit code and
  // output.
  std::pair<int, std::string> cli(const std::vector<std::string> &args,
                                  const ChildProcess::Environment &more = {}) {
    const fs::path out = run_ / "cli.out";
    std::vector<std::string> sh_args{"-c", "\"$0\" \"$@\" > " + out.string() + " 2>&1",
                                     (kBin / "rsca").string()};
    sh_args.insert(sh_args.end(), args.begin(), args.end());
    auto env = env_;
    env.insert(env.end(), more.begin(), more.end());
    ChildProcess cli("/bin/sh", sh_args, env);
    auto status = cli.wait_exit(60s);
    std::ifstream in(out);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    return {status && WIFEXITED(*status) ? WEXITSTATUS(*status) : -1, text};
  }

  void install(const std::string &application) {
    auto [rc, out] =
        cli({"install", "--sdrroot", kTestSdr.string(),
             (kTestSdr / fmt::format("dom/waveforms/{0}/{0}.sad.xml", application)).string()});
    INFO(out);
    REQUIRE(rc == 0);
  }

  // Installs an application of the test SDR root and creates it: the application as app.create
  // gives it.
  Json create(const std::string &application) {
    install(application);
    auto app = call("app.create", Json{{"application", application}});
    INFO((app ? std::string() : app.error().message));
    REQUIRE(app.has_value());
    return *app;
  }

  // Nothing of any application is left: no application, no allocation, no component process.
  void require_clean(const std::vector<long> &pids) {
    auto apps = call("app.list");
    REQUIRE(apps.has_value());
    CHECK(apps->at("applications").empty());
    auto devices = call("domain.devices");
    REQUIRE(devices.has_value());
    for (const auto &d : devices->at("devices")) {
      for (const auto &[name, c] : d.at("capacity").items()) {
        INFO(d.at("id") << " " << name);
        CHECK(c.at("allocated").get<double>() == Approx(0.0).margin(1e-9));
      }
      for (const auto &cpu : d.at("cpu_tasks")) {
        INFO(d.at("id") << " cpu tasks " << cpu.dump());
        CHECK(cpu.at("tasks").empty());
      }
    }
    for (long pid : pids) {
      INFO("component pid " << pid);
      CHECK(wait_for([&] { return !process_exists(pid); }));
    }
    auto nodes = call("domain.nodes");
    REQUIRE(nodes.has_value());
    // Waited for: a process gone from /proc (a zombie) is listed until the node's reaper has
    // reaped it, which a slow host (TSan: hostile_test's SIGKILLed orphans) shows.
    // Its shared memory too: no ring, no end of one, no process's page (freed as the process
    // is reaped).
    for (const auto &node : nodes->at("nodes")) {
      Json processes, shared;
      const bool reaped = wait_for([&] {
        auto status = client_->call_sync(node.at("address"), "node.status", Json::object(), 5s);
        REQUIRE(status.has_value());
        processes = status->at("processes");
        shared = status->value("shared_memory", Json::object());
        return processes.empty() && shared.value("rings", 0) == 0 && shared.value("ends", 0) == 0 &&
               shared.value("pages", 0) == 0 && shared.value("relays", 0) == 0;
      });
      INFO(node.at("address") << " still lists " << processes.dump() << ", shared memory "
                              << shared.dump());
      CHECK(reaped);
    }
  }

  // The process of node daemon `index` (from 1).
  pid_t node_pid(int index) const { return nodes_[index - 1]->pid(); }

  // Every component process the nodes run now.
  std::vector<long> running_pids() {
    std::vector<long> pids;
    for (int i = 0; i < static_cast<int>(nodes_.size()); ++i) {
      if (!nodes_[i])
        continue;
      auto status = client_->call_sync(fmt::format("rsca/node/node{}", i + 1), "node.status",
                                       Json::object(), 5s);
      if (status)
        for (const auto &p : status->at("processes"))
          pids.push_back(p.at("pid").get<long>());
    }
    return pids;
  }

  // Stops the domain daemon and starts a new one on the same repository; returns once the new
  // one answers (a call sent before then may reach the one that was stopping, and be lost).
  void restart_domaind(int registration_timeout_ms = kRegistrationTimeoutMs) {
    domaind_->signal(SIGTERM);
    REQUIRE(domaind_->wait_exit(5s).has_value());
    start_domaind(registration_timeout_ms);
    REQUIRE(wait_for([&] { return call("domain.nodes", Json::object(), 2s).has_value(); }));
  }

  // Kills the domain daemon as a crash would (SIGKILL): it stops nothing and tells nobody.
  void kill_domaind() {
    domaind_->signal(SIGKILL);
    REQUIRE(domaind_->wait_exit(5s).has_value());
  }

  // A domain daemon on this domain's repository.
  void start_domaind(int registration_timeout_ms) {
    std::vector<std::string> args{"--dmd",
                                  (kSource / "profiles/dom/domain/DomainManager.dmd.xml").string(),
                                  "--repository",
                                  (run_ / "repository").string(),
                                  "--registration-timeout-ms",
                                  std::to_string(registration_timeout_ms)};
    for (const auto &dir : exec_path_)
      args.insert(args.end(), {"--exec-path", dir.string()});
#ifdef RSCA_SANITIZE
    if (!default_delivery_kept)
      args.insert(args.end(), {"--delivery", "as-is"});
#endif
    domaind_ = std::make_unique<ChildProcess>((kBin / "rsca-domaind").string(), args, env_);
  }

  // Restarts the domain daemon finding component code in `dirs` first, then in the build's.
  void use_exec_path(const std::vector<fs::path> &dirs) {
    exec_path_ = dirs;
    exec_path_.push_back(kBin);
    restart_domaind();
  }

  // Starts one more node daemon (index: nodes so far + 1), with `more_args` of its options
  // (--log-max-kib 16), and waits until the domain knows it.
  void start_node(const fs::path &dcd, const std::vector<std::string> &more_args = {}) {
    auto before = call("domain.nodes");
    REQUIRE(before.has_value());
    const std::size_t known = before->at("nodes").size();
    launch_node(dcd, more_args);
    REQUIRE(wait_for([&] {
      auto r = call("domain.nodes");
      return r && r->at("nodes").size() > known;
    }));
  }

  // Stops a node daemon as its service manager would (SIGTERM); how it exited.
  std::optional<int> stop_node(int index, std::chrono::milliseconds limit = 10s) {
    nodes_[index - 1]->signal(SIGTERM);
    auto status = nodes_[index - 1]->wait_exit(limit);
    nodes_[index - 1].reset();
    return status;
  }

  void kill_node(int index) {
    nodes_[index - 1]->signal(SIGKILL);
    nodes_[index - 1]->wait_exit(5s);
    nodes_[index - 1].reset();
  }

  // Kills node `index` and starts it again at once, not waiting for the domain to see it go.
  void restart_node_at_once(int index, const fs::path &dcd) {
    kill_node(index);
    nodes_[index - 1] = start_node_process(dcd, index);
  }

  template <typename Predicate>
  static bool wait_for(Predicate done, std::chrono::milliseconds limit = kDomainWait) {
    return wait_until(done, limit);
  }

  const fs::path &run_dir() const {
    return run_;
  }
  // The environment that joins this domain (for programs a test starts itself).
  const ChildProcess::Environment &env() const {
    return env_;
  }

private:
  void launch_node(const fs::path &dcd, const std::vector<std::string> &more_args = {}) {
    nodes_.push_back(start_node_process(dcd, static_cast<int>(nodes_.size()) + 1, more_args));
  }

  std::unique_ptr<ChildProcess> start_node_process(const fs::path &dcd, int index,
                                                   const std::vector<std::string> &more_args = {}) {
    std::vector<std::string> args{"--dcd",
                                  dcd.string(),
                                  "--log-dir",
                                  (run_ / "logs").string(),
                                  "--exec-path",
                                  kBin.string(),
                                  "--control-socket",
                                  (run_ / fmt::format("node{}.sock", index)).string()};
    args.insert(args.end(), more_args.begin(), more_args.end());
#ifdef RSCA_SANITIZE
    if (const auto name = cache_seed::node_name(dcd);
        !default_delivery_kept && !cold_caches_kept && !name.empty()) {
      seeded_ = true; // cache_seed.hpp says why
      cache_seed::seed(kBin, run_ / "cache" / name);
    }
#endif
    return std::make_unique<ChildProcess>((kBin / "rsca-noded").string(), args, env_);
  }

public:
  // The test's own endpoint, for calls to nodes and components.
  rsca::control::Endpoint &client() {
    return *client_;
  }

private:
  fs::path run_;
  ChildProcess::Environment env_;
  std::unique_ptr<ChildProcess> domaind_;
  std::vector<fs::path> exec_path_; // the domain daemon's; empty: its default
  std::vector<std::unique_ptr<ChildProcess>> nodes_;
  bool seeded_ = false; // its nodes' caches started from the pool (cache_seed.hpp)
  std::shared_ptr<rsca::dds::Participant> participant_;
  std::unique_ptr<rsca::control::Endpoint> client_;
};

inline std::vector<long> pids_of(const Json &app) {
  std::vector<long> pids;
  for (const auto &c : app.at("components"))
    pids.push_back(c.at("pid").get<long>());
  return pids;
}

// The pid of component `id` of an application as app.show or app.create gives it; 0 when it has
// none.
inline long pid_of(const Json &app, const std::string &id) {
  for (const auto &c : app.at("components"))
    if (c.at("id") == id)
      return c.at("pid").get<long>();
  return 0;
}

inline long received(TestDomain &domain, const std::string &app) {
  auto q = domain.call("app.query",
                       Json{{"app", app}, {"component", "Consumer_1"}, {"ids", {"received"}}});
  if (!q)
    return -1;
  return q->at("properties").at("received").get<long>();
}

// A runtime connection as `connection.list` shows it; null when there is none.
inline Json runtime_connection(TestDomain &domain, const std::string &id) {
  auto list = domain.call("connection.list");
  REQUIRE(list.has_value());
  for (const auto &c : list->at("connections"))
    if (c.at("application") == "(runtime)" && c.at("id") == id)
      return c;
  return nullptr;
}

// Samples its provides end received; -1 while it is not connected.
inline long delivered(TestDomain &domain, const std::string &id) {
  const Json c = runtime_connection(domain, id);
  return c.is_null() || c.at("provides_state").is_null()
             ? -1
             : c.at("provides_state").at("samples").get<long>();
}

// The connections one port of a component or device has, from its own status.
inline long port_connections(TestDomain &domain, const std::string &address,
                             const std::string &port) {
  auto status = domain.client().call_sync(address, "component.status", Json::object(), 5s);
  if (!status)
    return -1;
  for (const auto &p : status->at("ports"))
    if (p.at("name") == port)
      return static_cast<long>(p.at("connections").size());
  return -1;
}

// A package the domain delivered to node `node` (a manifest of its cache) that holds a file named
// `program`, and that file's folder in it: what a node.execute of the program names (a node runs
// only programs of a package it took from its cache).
inline std::pair<Json, std::string>
cached_package_of(const TestDomain &domain, const std::string &node, const std::string &program) {
  const fs::path manifests = domain.run_dir() / "cache" / node / "manifests";
  for (const auto &entry : fs::directory_iterator(manifests)) {
    std::ifstream in(entry.path());
    const Json package = Json::parse(in);
    for (const auto &file : package.at("files"))
      if (fs::path(file.at("path").get<std::string>()).filename() == program)
        return {package, fs::path(file.at("path").get<std::string>()).parent_path().string()};
  }
  FAIL("no package of " << program << " in " << manifests);
  throw std::logic_error("unreachable");
}

// The package of `program` (a component of Healthy) that node1 took from its cache for Healthy,
// launched then released, and the program's folder in it: a node runs only programs of a
// package its domain delivered, which a test's own node.execute names too.
inline std::pair<Json, std::string> delivered_package_of(TestDomain &domain,
                                                         const std::string &program) {
  domain.create("Healthy");
  REQUIRE(domain.call("app.release", Json{{"app", "Healthy"}}).has_value());
  return cached_package_of(domain, "node1", program);
}

// Process `pid` frozen (SIGSTOP), as a hung one is; resumed however the test ends.
class FrozenProcess {
public:
  explicit FrozenProcess(pid_t pid) : pid_(pid) {
    REQUIRE(pid_ > 0); // never 0 or -1: a group, or every process
    REQUIRE(::kill(pid_, SIGSTOP) == 0);
  }
  ~FrozenProcess() { resume(); }
  FrozenProcess(const FrozenProcess &) = delete;
  FrozenProcess &operator=(const FrozenProcess &) = delete;
  void resume() {
    if (pid_ > 0)
      ::kill(pid_, SIGCONT);
    pid_ = 0;
  }

private:
  pid_t pid_;
};

// Node daemon `index` frozen: it answers no call and, past its DDS lease, the domain loses it.
class FrozenNode : public FrozenProcess {
public:
  FrozenNode(TestDomain &domain, int index) : FrozenProcess(domain.node_pid(index)) {}
};

} // namespace rsca::test
