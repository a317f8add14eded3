// Host facts for the GPP: the parsers on canned /proc text, and the real machine's values.
#include <chrono>
#include <filesystem>
#include <fstream>

#include <sys/sysinfo.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <catch2/catch.hpp>

#include "gpp/host_info.hpp"

using namespace std::chrono_literals;
using namespace rsca::gpp;
namespace fs = std::filesystem;

namespace {

constexpr std::uint64_t KiB = 1024;

// A /proc/stat with the given aggregate counters and a per-processor line that must be ignored.
std::string proc_stat(std::uint64_t user, std::uint64_t idle) {
  return "cpu  " + std::to_string(user) + " 0 0 " + std::to_string(idle) +
         " 0 0 0 0 0 0\ncpu0 1 1 1 1 1 1 1 1 0 0\nintr 12345\n";
}

} // namespace

TEST_CASE("meminfo gives total and available memory in bytes", "[host]") {
  const auto memory = parse_meminfo("MemTotal:       16318212 kB\n"
                                    "MemFree:         1204512 kB\n"
                                    "MemAvailable:    9876543 kB\n"
                                    "Buffers:          345678 kB\n"
                                    "HugePages_Total:       0\n");
  REQUIRE(memory.has_value());
  CHECK(memory->total_bytes == 16318212 * KiB);
  CHECK(memory->available_bytes == 9876543 * KiB);
}

TEST_CASE("meminfo without MemAvailable falls back to MemFree", "[host]") {
  const auto memory = parse_meminfo("MemTotal: 2048 kB\nMemFree: 512 kB\n");
  REQUIRE(memory.has_value());
  CHECK(memory->total_bytes == 2048 * KiB);
  CHECK(memory->available_bytes == 512 * KiB);
}

TEST_CASE("meminfo without MemTotal is an error", "[host]") {
  const auto memory = parse_meminfo("MemFree: 512 kB\nMemAvailable: 600 kB\n");
  REQUIRE_FALSE(memory.has_value());
  CHECK_THAT(memory.error().to_string(), Catch::Contains("no MemTotal entry"));
  CHECK_FALSE(parse_meminfo("").has_value());
}

TEST_CASE("cpuinfo processors are counted", "[host]") {
  const std::string x86 = "processor\t: 0\nvendor_id\t: GenuineIntel\nmodel name\t: Xeon\n\n"
                          "processor\t: 1\nvendor_id\t: GenuineIntel\nmodel name\t: Xeon\n\n";
  CHECK(parse_cpuinfo_processors(x86) == 2);
  // Older ARM kernels also print a "Processor" line naming the CPU model.
  const std::string arm = "Processor\t: ARMv7 Processor rev 4 (v7l)\nprocessor\t: 0\n"
                          "BogoMIPS\t: 38.40\n\nprocessor\t: 1\nBogoMIPS\t: 38.40\n\n"
                          "processor\t: 2\n\nprocessor\t: 3\n\nHardware\t: BCM2835\n";
  CHECK(parse_cpuinfo_processors(arm) == 4);
  CHECK(parse_cpuinfo_processors("") == 0);
}

TEST_CASE("/proc/stat gives busy and total CPU time", "[host]") {
  // user nice system idle iowait irq softirq steal guest guest_nice
  const auto times = parse_proc_stat("cpu  100 5 50 800 20 3 2 10 7 1\ncpu0 9 9 9 9 9 9 9 9 9 9\n");
  REQUIRE(times.has_value());
  CHECK(times->busy == 100 + 5 + 50 + 3 + 2 + 10); // guest time is already in user and nice
  CHECK(times->total == times->busy + 800 + 20);

  const auto old_kernel = parse_proc_stat("cpu 10 0 10 80\n");
  REQUIRE(old_kernel.has_value());
  CHECK(old_kernel->busy == 20);
  CHECK(old_kernel->total == 100);

  CHECK_FALSE(parse_proc_stat("cpu 1 2 3\n").has_value());
  CHECK_FALSE(parse_proc_stat("cpu0 1 2 3 4\nintr 5\n").has_value());
}

TEST_CASE("CPU utilisation is the busy share of the time between two samples", "[host]") {
  CHECK(cpu_utilisation({100, 1000}, {150, 1100}) == Approx(0.5));
  CHECK(cpu_utilisation({100, 1000}, {100, 1100}) == Approx(0.0));
  CHECK(cpu_utilisation({100, 1000}, {200, 1100}) == Approx(1.0));
  CHECK_FALSE(cpu_utilisation({100, 1000}, {100, 1000}).has_value()); // no time passed
  CHECK_FALSE(cpu_utilisation({100, 1000}, {50, 900}).has_value());   // counters went back
}

TEST_CASE("the CPU load sampler measures between consecutive samples", "[host]") {
  const auto file =
      fs::temp_directory_path() / ("rsca_host_info_stat_" + std::to_string(::getpid()));
  const auto write = [&](std::uint64_t user, std::uint64_t idle) {
    std::ofstream(file, std::ios::trunc) << proc_stat(user, idle);
  };
  write(100, 900);
  CpuLoadSampler sampler(file);
  write(130, 970); // 30 busy of 100
  CHECK(sampler.sample() == Approx(0.3));
  CHECK_FALSE(sampler.sample().has_value()); // no tick since
  write(230, 970);
  CHECK(sampler.sample() == Approx(1.0)); // 100 busy of 100
  fs::remove(file);
  CHECK_FALSE(sampler.sample().has_value());
}

TEST_CASE("this machine's host information is plausible", "[host]") {
  const auto host = read_host_info();
  struct utsname names {};
  REQUIRE(::uname(&names) == 0);
  CHECK(host.os_name == "Linux");
  CHECK(host.os_version == names.release);
  CHECK(host.processor_name == names.machine);
  char hostname[256] = {};
  REQUIRE(::gethostname(hostname, sizeof hostname - 1) == 0);
  CHECK(host.hostname == hostname);

  CHECK(host.cpu_cores >= 1);
  CHECK(host.cpu_cores <= static_cast<unsigned>(::sysconf(_SC_NPROCESSORS_CONF)));

  struct sysinfo info {};
  REQUIRE(::sysinfo(&info) == 0);
  CHECK(host.memory_total_bytes == std::uint64_t{info.totalram} * info.mem_unit);
  CHECK(host.memory_available_bytes > 0);
  CHECK(host.memory_available_bytes <= host.memory_total_bytes);
}

TEST_CASE("this machine's CPU load is between 0 and 1", "[host]") {
  CpuLoadSampler sampler;
  // Keeps this thread busy until a clock tick has passed (at most a few tens of milliseconds).
  std::optional<double> load;
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  volatile std::uint64_t spin = 0;
  while (!load && std::chrono::steady_clock::now() < deadline) {
    for (int i = 0; i < 100000; ++i) {
      spin = spin + 1;
    }
    load = sampler.sample();
  }
  REQUIRE(load.has_value());
  CHECK(*load >= 0.0);
  CHECK(*load <= 1.0);
}
