// What the GPP tells the domain about its host: processors, memory, operating system, and the
// CPU load between two samples. Read from /proc and uname(2); the parsing functions take the
// file text so they can be tested on canned text.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "common/diagnostic.hpp"

namespace rsca::gpp {

struct HostInfo {
  std::string hostname;
  std::string os_name;        // uname sysname, "Linux"
  std::string os_version;     // uname release, the kernel version
  std::string processor_name; // uname machine, e.g. "x86_64", "aarch64"
  unsigned cpu_cores = 0;     // logical processors
  std::uint64_t memory_total_bytes = 0;
  std::uint64_t memory_available_bytes = 0; // what can be allocated without swapping
};

// The host as it is now. Facts that cannot be read keep their zero or empty value.
HostInfo read_host_info();

struct MemoryInfo {
  std::uint64_t total_bytes = 0;
  std::uint64_t available_bytes = 0;
};

// /proc/meminfo: MemTotal and MemAvailable (MemFree on kernels without it), in bytes.
Expected<MemoryInfo> parse_meminfo(std::string_view text);

// /proc/cpuinfo: the number of "processor" entries; 0 when there is none.
unsigned parse_cpuinfo_processors(std::string_view text);

// Cumulative CPU time of all processors, in clock ticks.
struct CpuTimes {
  std::uint64_t busy = 0;  // user, nice, system, irq, softirq, steal
  std::uint64_t total = 0; // busy plus idle and iowait
};

// /proc/stat: the aggregate "cpu" line.
Expected<CpuTimes> parse_proc_stat(std::string_view text);

// The fraction (0 to 1) of CPU time spent busy between two samples; nullopt when no time passed
// between them or the later one is not later.
std::optional<double> cpu_utilisation(const CpuTimes &earlier, const CpuTimes &later);

// The host's CPU utilisation between consecutive calls of sample().
class CpuLoadSampler {
public:
  // Takes the first sample.
  explicit CpuLoadSampler(std::filesystem::path stat_file = "/proc/stat");

  // Utilisation (0 to 1, all processors together) since the previous sample; nullopt when the
  // file cannot be read or no clock tick has passed since the previous sample (which is then
  // kept, so the next call measures over the longer interval).
  std::optional<double> sample();

private:
  std::optional<CpuTimes> read() const;

  std::filesystem::path stat_file_;
  std::optional<CpuTimes> previous_;
};

// The whole of a small file such as those in /proc (opened O_CLOEXEC, read to the end);
// nullopt when it cannot be read.
std::optional<std::string> read_proc_file(const std::filesystem::path &path);

} // namespace rsca::gpp
