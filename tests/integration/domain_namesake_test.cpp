// One name, one holder (issue 39): a second domain daemon or node daemon of a name a live one
// already serves, on the same DDS domain and tag, refuses to start and says who holds the name;
// the holder's domain, nodes and applications are as they were. (A node killed and started again
// at once is still its own restart: domain_node_failure_test.cpp.)
#include <signal.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <set>
#include <string>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "common/host_name.hpp"
#include "domain_fixture.hpp"

using namespace rsca::test;
using namespace std::chrono_literals;
using rsca::control::Json;

namespace {

std::string namesake_log(const fs::path &file) {
  std::ifstream in(file);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The namesake `daemon` exits on its own, refused: its exit code, or -1 when it still runs.
int refused_exit_code(ChildProcess &daemon) {
  const auto status = daemon.wait_exit(20s);
  if (!status)
    return -1;
  return WIFEXITED(*status) ? WEXITSTATUS(*status) : 128 + WTERMSIG(*status);
}

// The command line of process `pid`, its arguments joined by spaces.
std::string command_line_of(long pid) {
  std::string text = namesake_log(fmt::format("/proc/{}/cmdline", pid));
  std::replace(text.begin(), text.end(), '\0', ' ');
  return text;
}

// The holder's domain is as it was: both nodes registered, none lost, the application whole and
// every one of its processes running.
void require_untouched(TestDomain &domain, const Json &app) {
  auto nodes = domain.call("domain.nodes");
  REQUIRE(nodes.has_value());
  CHECK(nodes->at("nodes").size() == 2);
  CHECK(nodes->at("lost").empty());
  auto shown = domain.call("app.show", Json{{"app", app.at("name")}});
  REQUIRE(shown.has_value());
  CHECK(shown->at("state") == "running");
  CHECK(shown->at("exited").empty());
  for (const long pid : pids_of(app))
    CHECK(process_exists(pid));
}

// Stops whatever daemons `rsca domain up` started in `run` (their pid files) when the test ends,
// failed or not: an `up` that wrongly went ahead leaves nothing running after its test.
class UpDaemons {
public:
  explicit UpDaemons(fs::path run) : run_(std::move(run)) {}
  ~UpDaemons() {
    std::error_code ec;
    for (const auto &entry : fs::directory_iterator(run_, ec))
      if (entry.path().extension() == ".pid")
        if (const long pid = std::atol(namesake_log(entry.path()).c_str()); pid > 0)
          ::kill(static_cast<pid_t>(pid), SIGKILL);
  }
  UpDaemons(const UpDaemons &) = delete;
  UpDaemons &operator=(const UpDaemons &) = delete;

private:
  fs::path run_;
};

} // namespace

TEST_CASE("a second domain daemon of a live domain's name, DDS domain and tag refuses to start, "
          "naming the first, and the first keeps its nodes and applications",
          "[integration][domain][namesake]") {
  TestDomain domain;
  const Json app = domain.create("Healthy");
  const fs::path log = domain.run_dir() / "namesake-domaind.log";
  const fs::path repository = domain.run_dir() / "namesake-repository";
  ChildProcess namesake((kBin / "rsca-domaind").string(),
                        {"--dmd", (kSource / "profiles/dom/domain/DomainManager.dmd.xml").string(),
                         "--repository", repository.string()},
                        domain.env(), log);
  const int rc = refused_exit_code(namesake);
  const std::string said = namesake_log(log);
  INFO(said);
  CHECK(rc == 1);
  CHECK_THAT(said, Catch::Contains("name-taken"));
  // It names the holder: a live domain daemon serving this domain's repository, on this host.
  const std::string prefix = "domain rsca is served by pid ";
  const auto at = said.find(prefix);
  REQUIRE(at != std::string::npos);
  const long holder = std::stol(said.substr(at + prefix.size()));
  CHECK(holder != namesake.pid());
  CHECK_THAT(command_line_of(holder),
             Catch::Contains("rsca-domaind") &&
                 Catch::Contains((domain.run_dir() / "repository").string()));
  CHECK_THAT(said, Catch::Contains(fmt::format("on host {} (DDS domain ", rsca::host_name())));
  // Refused before it opened a store: nothing of its own left behind.
  CHECK_FALSE(fs::exists(repository));
  require_untouched(domain, app);
  REQUIRE(domain.call("app.release", Json{{"app", "Healthy"}}).has_value());
  domain.require_clean(pids_of(app));
}

TEST_CASE("a second node daemon of a live node's name is refused with both identities named, and "
          "the first stays registered with its application running",
          "[integration][domain][namesake]") {
  TestDomain domain;
  const Json app = domain.create("Healthy"); // first fit: on node1
  auto nodes = domain.call("domain.nodes");
  REQUIRE(nodes.has_value());
  long node1 = 0;
  for (const auto &n : nodes->at("nodes"))
    if (n.at("name") == "node1")
      node1 = n.at("pid").get<long>();
  REQUIRE(node1 > 0);
  const fs::path log = domain.run_dir() / "namesake-noded.log";
  const fs::path cache = domain.run_dir() / "namesake-cache";
  const fs::path dcd = TestDomain::shipped_nodes(1).front(); // node1's own DCD, as if copied
  ChildProcess namesake((kBin / "rsca-noded").string(),
                        {"--dcd", dcd.string(), "--log-dir",
                         (domain.run_dir() / "namesake-logs").string(), "--cache-dir",
                         cache.string(), "--exec-path", kBin.string()},
                        domain.env(), log);
  const int rc = refused_exit_code(namesake);
  const std::string said = namesake_log(log);
  INFO(said);
  CHECK(rc == 1);
  CHECK_THAT(said, Catch::Contains("name-taken"));
  const std::string host = rsca::host_name();
  CHECK_THAT(
      said, Catch::Contains(fmt::format("node node1 is served by pid {} on host {}", node1, host)));
  CHECK_THAT(said, Catch::Contains(fmt::format("this node daemon (pid {} on host {}, DCD {})",
                                               namesake.pid(), host, dcd.string())));
  // Refused before its cache, devices or shared memory existed.
  CHECK_FALSE(fs::exists(cache));
  require_untouched(domain, app);
  // node1 is the same run, and still does what the domain asks of it.
  auto status = domain.call_node(1, "node.status");
  REQUIRE(status.has_value());
  CHECK(status->at("pid").get<long>() == node1);
  std::set<long> running;
  for (const auto &p : status->at("processes"))
    running.insert(p.at("pid").get<long>());
  for (const long pid : pids_of(app))
    CHECK(running.count(pid) == 1);
  REQUIRE(domain.call("app.release", Json{{"app", "Healthy"}}).has_value());
  domain.require_clean(pids_of(app));
}

TEST_CASE("rsca domain up on the DDS domain and tag of a live domain refuses, naming its daemon, "
          "and starts nothing",
          "[integration][domain][namesake][cli]") {
  TestDomain domain;
  const Json app = domain.create("Healthy");
  const fs::path second = domain.run_dir() / "second";
  const UpDaemons started(second);
  auto [rc, out] = domain.cli({"--sdrroot", (kSource / "profiles").string(), "domain", "up",
                               "--nodes", "1", "--run-dir", second.string()});
  INFO(out);
  CHECK(rc == 5);
  CHECK_THAT(out, Catch::Contains("domain rsca is served by pid ") &&
                      Catch::Contains(fmt::format("on host {} (DDS domain ", rsca::host_name())) &&
                      Catch::Contains("nothing started"));
  // No daemon of its own: no pid file, no log.
  for (const char *file : {"domaind.pid", "node1.pid", "domaind.log", "node1.log"})
    CHECK_FALSE(fs::exists(second / file));
  require_untouched(domain, app);
  REQUIRE(domain.call("app.release", Json{{"app", "Healthy"}}).has_value());
  domain.require_clean(pids_of(app));
}
