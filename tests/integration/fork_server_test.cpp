// Fork servers on a real node (gpp/fork_servers.hpp): the processes of one executable are forked
// from one fork server of it, yet are the node's children, in process groups of their own, with
// their own command lines; a crash of one is reported; released, they are gone, and the servers go
// with their node. A GPP whose fork_server is false executes every process.
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <catch2/catch.hpp>

#include "domain_fixture.hpp"
#include "process/fork_request.hpp"

using namespace rsca::test;

namespace {

struct ProcessFacts {
  long pid = 0;
  long parent = 0;
  long group = 0;
  std::string command_line; // NULs as spaces
  std::string executable;
  // The environment the kernel shows (/proc/PID/environ): the one the process was executed with.
  // A process forked from a fork server never executed: it shows its server's, which names the
  // server's socket (process/fork_request.hpp's kForkServerVariable), whatever the process set
  // afterwards. Unlike the memory layout, this holds without address randomisation too.
  std::string exec_environment; // NULs as newlines
};

bool executed_as_fork_server(const ProcessFacts &facts) {
  return facts.exec_environment.find(std::string("\n") + rsca::process::kForkServerVariable +
                                     "=") != std::string::npos;
}

// A /proc file's bytes; what was read when the process ends meanwhile (an ifstream would throw).
std::string proc_file(const fs::path &file) {
  std::string text;
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0)
    return text;
  char buffer[4096];
  for (ssize_t n; (n = ::read(fd, buffer, sizeof buffer)) > 0;)
    text.append(buffer, static_cast<std::size_t>(n));
  ::close(fd);
  return text;
}

ProcessFacts facts_of(long pid) {
  ProcessFacts facts{pid, 0, 0, {}, {}, {}};
  const fs::path proc = fmt::format("/proc/{}", pid);
  std::ifstream stat(proc / "stat");
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  const auto paren = text.rfind(')');
  if (paren != std::string::npos) {
    std::istringstream rest(text.substr(paren + 2));
    std::string state;
    rest >> state >> facts.parent >> facts.group;
  }
  std::ifstream cmdline(proc / "cmdline", std::ios::binary);
  facts.command_line.assign(std::istreambuf_iterator<char>(cmdline),
                            std::istreambuf_iterator<char>());
  for (auto &c : facts.command_line)
    c = c == '\0' ? ' ' : c;
  std::error_code ec;
  facts.executable = fs::read_symlink(proc / "exe", ec).string();
  facts.exec_environment = "\n" + proc_file(proc / "environ");
  for (auto &c : facts.exec_environment)
    c = c == '\0' ? '\n' : c;
  return facts;
}

// The node's children that are fork servers.
std::vector<ProcessFacts> fork_servers_of(pid_t node) {
  std::vector<ProcessFacts> servers;
  for (const auto &entry : fs::directory_iterator("/proc")) {
    const auto name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos)
      continue;
    auto facts = facts_of(std::stol(name));
    if (facts.parent == node && facts.command_line.find("--rsca-fork-server") != std::string::npos)
      servers.push_back(std::move(facts));
  }
  return servers;
}

// Launches the shipped ProducerConsumer (a producer and a consumer) as `name`: its pids.
std::vector<long> launch(TestDomain &domain, const std::string &name) {
  const auto sad =
      (kSource / "profiles/dom/waveforms/ProducerConsumer/ProducerConsumer.sad.xml").string();
  auto [rc, out] = domain.cli({"launch", sad, "--name", name});
  INFO(out);
  REQUIRE(rc == 0);
  auto shown = domain.call("app.show", Json{{"app", name}});
  REQUIRE(shown.has_value());
  return pids_of(*shown);
}

std::set<long> pids_in(const std::vector<ProcessFacts> &processes) {
  std::set<long> pids;
  for (const auto &process : processes)
    pids.insert(process.pid);
  return pids;
}

} // namespace

TEST_CASE("a node forks the processes of an executable from a fork server of it, as its "
          "children, in groups of their own, with their own command lines",
          "[integration][fork_server]") {
  std::vector<ProcessFacts> servers;
  {
    TestDomain domain(1);
    const pid_t node = domain.node_pid(1);
    const auto pids = launch(domain, "a");
    REQUIRE(pids.size() == 2);
    servers = fork_servers_of(node);
    REQUIRE(servers.size() == 2); // one per executable: the producer's, the consumer's
    std::set<std::string> served;
    for (const auto &server : servers) {
      served.insert(server.executable);
      CHECK(executed_as_fork_server(server));
    }
    for (const long pid : pids) {
      const auto facts = facts_of(pid);
      INFO(facts.command_line);
      CHECK(facts.parent == node);
      CHECK(facts.group == pid);
      CHECK(served.count(facts.executable) == 1);
      CHECK(executed_as_fork_server(facts)); // forked from one, never executed
      CHECK_THAT(facts.command_line, Catch::Contains("COMPONENT_IDENTIFIER"));
    }
    // A forked process that dies is reported as any: the application is degraded.
    REQUIRE(::kill(static_cast<pid_t>(pids.front()), SIGKILL) == 0);
    CHECK(TestDomain::wait_for([&] {
      auto shown = domain.call("app.show", Json{{"app", "a"}});
      return shown && shown->value("state", "") == "degraded";
    }));
    REQUIRE(domain.call("app.release", Json{{"app", "a"}}).has_value());
    domain.require_clean(pids);
    // The servers stay while their node runs, and fork the next launch's processes.
    const auto again = launch(domain, "a");
    CHECK(pids_in(fork_servers_of(node)) == pids_in(servers));
    for (const long pid : again)
      CHECK(facts_of(pid).parent == node);
    REQUIRE(domain.call("app.release", Json{{"app", "a"}}).has_value());
    domain.require_clean(again);
  }
  // They go with their node.
  for (const auto &server : servers) {
    INFO("fork server " << server.pid);
    CHECK(TestDomain::wait_for([&] { return !process_exists(server.pid); }));
  }
}

TEST_CASE("a node whose GPP's fork_server is false executes every process",
          "[integration][fork_server]") {
  TestDomain domain({kTestSdr / "dev/nodes/exec1/DeviceManager.dcd.xml"});
  const pid_t node = domain.node_pid(1);
  const auto pids = launch(domain, "a");
  REQUIRE(pids.size() == 2);
  CHECK(fork_servers_of(node).empty());
  for (const long pid : pids) {
    const auto facts = facts_of(pid);
    CHECK(facts.parent == node);
    CHECK(facts.group == pid);
    CHECK_THAT(facts.command_line, Catch::Contains("COMPONENT_IDENTIFIER"));
    CHECK_FALSE(executed_as_fork_server(facts)); // executed: its own environment
  }
  REQUIRE(domain.call("app.release", Json{{"app", "a"}}).has_value());
  domain.require_clean(pids);
}

namespace {

std::string cpus_allowed(long pid) {
  std::ifstream status(fmt::format("/proc/{}/status", pid));
  for (std::string line; std::getline(status, line);)
    if (line.rfind("Cpus_allowed_list:", 0) == 0)
      return line.substr(line.find_first_not_of(" \t", line.find(':') + 1));
  return {};
}

} // namespace

TEST_CASE("a process forked after one pinned to a CPU runs on the node's CPUs, not that one's",
          "[integration][fork_server]") {
  // A node that leaves periodic components free (the producer is one), so that only an
  // instance's affinity pins a process.
  TestDomain domain({kTestSdr / "dev/nodes/free1/DeviceManager.dcd.xml"});
  // The first process of the producer's executable is pinned: its server starts then.
  const auto pinned = pids_of(domain.create("Pinned"));
  REQUIRE(pinned.size() == 1);
  CHECK(cpus_allowed(pinned.front()) == "0");
  const auto pids = launch(domain, "a");
  REQUIRE(pids.size() == 2);
  const std::string node_cpus = cpus_allowed(domain.node_pid(1));
  for (const long pid : pids)
    CHECK(cpus_allowed(pid) == node_cpus);
  for (const auto &server : fork_servers_of(domain.node_pid(1)))
    CHECK(cpus_allowed(server.pid) == node_cpus);
}
