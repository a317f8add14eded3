// Network hosts for the multihost tests: tools/hosts makes network namespaces joined by a bridge
// (the same script users run for the demo), this guard removes them when it goes, also when the
// test fails. Where namespaces cannot be made (no privileges or kernel support: tools/hosts probe
// exits 77) the test process exits with 77, which ctest reports as skipped, never as passed; any
// other failure of the probe (iproute2 missing) fails the test.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace rsca::test {

inline const std::filesystem::path kHostsTool =
    std::filesystem::path(RSCA_SOURCE_DIR) / "tools/hosts";

// The exit code ctest reads as "skipped" (SKIP_RETURN_CODE in tests/CMakeLists.txt).
inline constexpr int kSkipped = 77;

// Runs `command` with a shell; its exit code and standard output.
inline std::pair<int, std::string> run_command(const std::string &command) {
  std::string out;
  FILE *pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr)
    return {-1, out};
  char buffer[4096];
  while (std::fgets(buffer, sizeof(buffer), pipe) != nullptr)
    out += buffer;
  const int status = ::pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

// Where `ip` is: the multihost processes are started as `ip netns exec <host> <program> ...`.
inline std::string ip_program() {
  for (const char *path : {"/usr/sbin/ip", "/sbin/ip", "/usr/bin/ip", "/bin/ip"})
    if (::access(path, X_OK) == 0)
      return path;
  return "ip";
}

class NetHosts {
public:
  // `count` hosts, named rsca<pid>t<n>-h1..: the pid lets `tools/hosts down --stale` find a set
  // whose test died; n tells apart the sets of one test process.
  explicit NetHosts(int count) {
    static std::atomic<int> sets{0};
    // Skipped only where the probe says hosts cannot be made here (no privileges or kernel
    // support); any other failure of the probe is the test's.
    if (auto [rc, out] = run_command(kHostsTool.string() + " probe 2>&1"); rc == kSkipped) {
      std::cout << "skipped: " << out << std::flush;
      std::exit(kSkipped);
    } else if (rc != 0) {
      FAIL("tools/hosts probe failed (exit " << rc << "): " << out);
    }
    name_ = fmt::format("rsca{}t{}", ::getpid(), ++sets);
    auto [rc, out] =
        run_command(fmt::format("{} up {} --name {} 2>&1", kHostsTool.string(), count, name_));
    if (rc != 0)
      FAIL("tools/hosts up: " << out);
    std::istringstream lines(out);
    std::string ns, address, interface;
    while (lines >> ns >> address >> interface)
      hosts_.push_back({ns, address, interface});
    if (static_cast<int>(hosts_.size()) != count) {
      down(); // the destructor does not run when the constructor fails
      FAIL("tools/hosts up " << count << " said: " << out);
    }
  }
  ~NetHosts() { down(); }
  NetHosts(const NetHosts &) = delete;
  NetHosts &operator=(const NetHosts &) = delete;

  // Host `index`, from 1: its namespace, address and interface.
  const std::string &ns(int index) const { return hosts_.at(index - 1).ns; }
  const std::string &address(int index) const { return hosts_.at(index - 1).address; }
  const std::string &interface(int index) const { return hosts_.at(index - 1).interface; }

  // The argv that runs `program args...` on host `index`.
  std::vector<std::string> on_host(int index, const std::string &program,
                                   const std::vector<std::string> &args) const {
    std::vector<std::string> argv{"netns", "exec", ns(index), program};
    argv.insert(argv.end(), args.begin(), args.end());
    return argv;
  }

  // Bytes host `index` received on its network interface (not its loopback).
  std::uint64_t received_bytes(int index) const {
    auto [rc, out] = run_command(fmt::format("{} -n {} -s -j link show {} 2>/dev/null",
                                             ip_program(), ns(index), interface(index)));
    const auto json = nlohmann::json::parse(out, nullptr, false);
    if (rc != 0 || json.is_discarded() || !json.is_array() || json.empty())
      return 0;
    return json[0].at("stats64").at("rx").at("bytes").get<std::uint64_t>();
  }

  // Takes host `index`'s link down or up, as a cable pulled and put back.
  void set_link(int index, bool up) const {
    auto [rc, out] = run_command(fmt::format("{} -n {} link set {} {} 2>&1", ip_program(),
                                             ns(index), interface(index), up ? "up" : "down"));
    REQUIRE(rc == 0);
  }

  // Limits what host `index` sends to `rate` (tc's token bucket, "50mbit"): a slow link.
  void limit_rate(int index, const std::string &rate) const {
    auto [rc, out] = run_command(fmt::format(
        "{} netns exec {} tc qdisc replace dev {} root tbf rate {} burst 64kb latency 200ms 2>&1",
        ip_program(), ns(index), interface(index), rate));
    INFO(out);
    REQUIRE(rc == 0);
  }

private:
  void down() const { run_command(fmt::format("{} down {} 2>&1", kHostsTool.string(), name_)); }

  struct Host {
    std::string ns, address, interface;
  };
  std::string name_;
  std::vector<Host> hosts_;
};

} // namespace rsca::test
