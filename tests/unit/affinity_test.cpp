// CPU lists (common/cpu_list.hpp) and the GPP's affinity (gpp/affinity.hpp): what a directive
// means on a host, read from a /sys made for the test, and what applying it does to a process.
#include "common/cpu_list.hpp"
#include "gpp/affinity.hpp"

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <sched.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "temp_dir.hpp"

namespace fs = std::filesystem;
using namespace rsca;
using rsca::protocol::node::AffinityDirective;

namespace {

void write(const fs::path &file, const std::string &text) {
  fs::create_directories(file.parent_path());
  std::ofstream(file) << text << '\n';
}

// A /sys with CPUs 0-7 online, NUMA node 0 (CPUs 0-3), node 1 (4-7), a NIC near node 1 and a
// virtual interface with no device.
struct FakeSys {
  test::TempDir dir;
  FakeSys() {
    write(dir.path() / "devices/system/cpu/online", "0-7");
    write(dir.path() / "devices/system/node/node0/cpulist", "0-3");
    write(dir.path() / "devices/system/node/node1/cpulist", "4-7");
    write(dir.path() / "class/net/eth1/device/local_cpulist", "4-7");
    fs::create_directories(dir.path() / "class/net/veth0");
  }
  std::string root() const { return dir.path().string(); }
};

std::string message(const Error &e) {
  return e.diagnostics().front().message;
}

} // namespace

TEST_CASE("CPU lists", "[affinity]") {
  CHECK(*parse_cpu_list("0-3,6") == std::vector<unsigned>{0, 1, 2, 3, 6});
  CHECK(*parse_cpu_list(" 5 ") == std::vector<unsigned>{5});
  CHECK(*parse_cpu_list("3,1-2,2") == std::vector<unsigned>{1, 2, 3});
  for (const char *bad : {"", " ", "a", "1-", "-1", "3-1", "1,,2", "1.5", "4096", "0-99999"}) {
    CAPTURE(bad);
    CHECK_FALSE(parse_cpu_list(bad).has_value());
  }
}

TEST_CASE("affinity directives resolve against the host", "[affinity]") {
  FakeSys sys;
  auto resolve = [&](std::string directive, std::string value) {
    return gpp::resolve_affinity(AffinityDirective{std::move(directive), std::move(value)},
                                 sys.root());
  };
  CHECK(resolve("cpu", "1,6")->cpus == std::vector<unsigned>{1, 6});
  CHECK(resolve("socket", "1")->cpus == std::vector<unsigned>{4, 5, 6, 7});
  CHECK(resolve("socket", "0-1")->cpus.size() == 8);
  CHECK(resolve("nic", "eth1")->cpus == std::vector<unsigned>{4, 5, 6, 7});
  auto nice = resolve("nice", "10");
  REQUIRE(nice.has_value());
  CHECK(nice->cpus.empty());
  CHECK(nice->nice == 10);

  CHECK_THAT(message(resolve("cpu", "9").error()), Catch::Contains("cpu 9 is not online"));
  CHECK_THAT(message(resolve("socket", "2").error()), Catch::Contains("NUMA node 2 is not"));
  CHECK_THAT(message(resolve("nic", "veth0").error()), Catch::Contains("no device"));
  CHECK_THAT(message(resolve("nic", "wlan9").error()), Catch::Contains("not on this host"));
  // A name that would reach another /sys path is refused before any path is made of it.
  CHECK_THAT(message(resolve("nic", "../../x").error()),
             Catch::Contains("not a network interface name"));
  CHECK(!resolve("nice", "20").has_value());
  CHECK(!resolve("nice", "x").has_value());
  CHECK(!resolve("cgroup", "rt").has_value());
  CHECK(!resolve("cpu", std::string(300, '1')).has_value());
}

TEST_CASE("an affinity applied to a process pins it and sets its nice value", "[affinity]") {
  cpu_set_t own;
  REQUIRE(sched_getaffinity(0, sizeof(own), &own) == 0);
  unsigned first = 0;
  while (!CPU_ISSET(first, &own))
    ++first;
  const pid_t child = fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    pause(); // until killed
    _exit(0);
  }
  const auto applied = gpp::apply_placement(child, gpp::ProcessPlacement{{first}, 5});
  cpu_set_t set;
  REQUIRE(sched_getaffinity(child, sizeof(set), &set) == 0);
  errno = 0;
  const int nice = getpriority(PRIO_PROCESS, static_cast<id_t>(child));
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  INFO((applied ? std::string() : applied.error().to_string()));
  REQUIRE(applied.has_value());
  CHECK(CPU_COUNT(&set) == 1);
  CHECK(CPU_ISSET(first, &set));
  CHECK(nice == 5);
}
