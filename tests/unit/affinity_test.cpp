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
  const std::vector<unsigned> all{0, 1, 2, 3, 4, 5, 6, 7};
  auto resolve = [&](std::string directive, std::string value,
                     const std::vector<unsigned> &usable) {
    return gpp::resolve_affinity(AffinityDirective{std::move(directive), std::move(value)},
                                 sys.root(), usable);
  };
  auto resolve_any = [&](std::string directive, std::string value) {
    return resolve(std::move(directive), std::move(value), all);
  };
  CHECK(resolve_any("cpu", "1,6")->cpus == std::vector<unsigned>{1, 6});
  CHECK(resolve_any("socket", "1")->cpus == std::vector<unsigned>{4, 5, 6, 7});
  CHECK(resolve_any("socket", "0-1")->cpus.size() == 8);
  CHECK(resolve_any("nic", "eth1")->cpus == std::vector<unsigned>{4, 5, 6, 7});
  auto nice = resolve_any("nice", "10");
  REQUIRE(nice.has_value());
  CHECK(nice->cpus.empty());
  CHECK(nice->nice == 10);

  CHECK_THAT(message(resolve_any("cpu", "9").error()), Catch::Contains("cpu 9 is not online"));
  CHECK_THAT(message(resolve_any("socket", "2").error()), Catch::Contains("NUMA node 2 is not"));
  CHECK_THAT(message(resolve_any("nic", "veth0").error()), Catch::Contains("no device"));
  CHECK_THAT(message(resolve_any("nic", "wlan9").error()), Catch::Contains("not on this host"));
  // A name that would reach another /sys path is refused before any path is made of it.
  CHECK_THAT(message(resolve_any("nic", "../../x").error()),
             Catch::Contains("not a network interface name"));
  CHECK(!resolve_any("nice", "20").has_value());
  CHECK(!resolve_any("nice", "x").has_value());
  CHECK(!resolve_any("cgroup", "rt").has_value());
  CHECK(!resolve_any("cpu", std::string(300, '1')).has_value());
  // Online is not enough: the node (in a cpuset, say) may use only some CPUs.
  CHECK_THAT(message(resolve("socket", "1", {0, 1, 2, 3, 4}).error()),
             Catch::Contains("cpu 5 is not one this node may use"));
  CHECK(resolve("cpu", "4", {0, 1, 2, 3, 4}).has_value());
}

TEST_CASE("a process started while its parent thread is pinned starts on those CPUs",
          "[affinity]") {
  const auto usable = gpp::usable_cpus();
  REQUIRE_FALSE(usable.empty());
  const unsigned last = usable.back();
  pid_t child = -1;
  {
    gpp::ScopedThreadCpus pinned({last});
    REQUIRE(pinned.pinned());
    child = fork();
    REQUIRE(child >= 0);
    if (child == 0) {
      pause(); // until killed
      _exit(0);
    }
  }
  cpu_set_t child_set;
  const bool read = sched_getaffinity(child, sizeof(child_set), &child_set) == 0;
  // The nice value goes on the child: one above this process's, which needs no privilege.
  errno = 0;
  const int own_nice = getpriority(PRIO_PROCESS, 0);
  const auto niced = gpp::apply_nice(child, gpp::ProcessPlacement{{}, std::min(own_nice + 1, 19)});
  errno = 0;
  const int child_nice = getpriority(PRIO_PROCESS, static_cast<id_t>(child));
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  REQUIRE(read);
  CHECK(CPU_COUNT(&child_set) == 1);
  CHECK(CPU_ISSET(last, &child_set));
  // This thread has its own mask back.
  CHECK(gpp::usable_cpus() == usable);
  INFO((niced ? std::string() : niced.error().to_string()));
  REQUIRE(niced.has_value());
  CHECK(child_nice == std::min(own_nice + 1, 19));
  // A process already gone is no error.
  CHECK(gpp::apply_nice(child, gpp::ProcessPlacement{{}, 5}).has_value());
}
