// A process's figures as Linux keeps them in /proc: CPU time, resident memory, threads; and CPU %
// made from two readings. For `rsca top` (node.top, domain.top): each daemon reports itself and
// the processes it runs.
//
// Everything comes from /proc/PID/stat alone (utime, stime, num_threads, starttime, rss): one
// read is one consistent snapshot, and its rss is the counter /proc/PID/status shows as VmRSS.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string_view>

#include <sys/types.h>

namespace rsca::process {

// The fields of one /proc/PID/stat line that the figures use, in the kernel's units.
struct StatLine {
  std::uint64_t cpu_ticks = 0;   // utime + stime, in clock ticks
  std::uint64_t threads = 0;     // num_threads
  std::uint64_t start_ticks = 0; // starttime: after boot, in clock ticks
  std::uint64_t rss_pages = 0;
};

// Reads a /proc/PID/stat line. The command name (field 2) is between parentheses and may itself
// hold spaces and parentheses, so the fields after it are counted from its last ')'. Nothing for
// a line that does not have them.
std::optional<StatLine> parse_stat_line(std::string_view line);

// One reading of a process.
struct Reading {
  StatLine stat;
  std::chrono::steady_clock::time_point at;
};

// CPU % (of one CPU, as top(1) counts it: a process busy on two CPUs is 200) between two readings
// of the same process; 0 when no time passed.
double cpu_percent(std::uint64_t ticks_before, std::uint64_t ticks_after,
                   std::chrono::nanoseconds elapsed, long ticks_per_second);

// What a daemon reports of a process.
struct Figures {
  double cpu_percent = 0;
  std::uint64_t rss_bytes = 0;
  std::uint64_t threads = 0;
};

// Reads processes' figures, each CPU % since the last reading of the same process (the first one:
// since the process started). It keeps the last reading of each process instead of sampling over
// an interval, so a request is answered at once and no handler thread sleeps. Readings closer
// than kMinInterval to the last one give the last CPU % again: two callers at once would
// otherwise each see a few milliseconds' worth, mostly rounding. Thread-safe.
class CpuSampler {
public:
  static constexpr std::chrono::milliseconds kMinInterval{200};

  // Nothing for a process that is gone (or unreadable).
  std::optional<Figures> read(pid_t pid);
  // Forgets the processes not in `alive` (pids are reused: a new process must not be measured
  // against an old one's reading).
  template <typename Pids>
  void keep_only(const Pids &alive) {
    std::lock_guard lock(mutex_);
    for (auto it = last_.begin(); it != last_.end();)
      it = alive.count(it->first) == 0 ? last_.erase(it) : std::next(it);
  }

private:
  struct Last {
    Reading reading;
    double cpu_percent = 0;
  };
  double since_start(const StatLine &stat) const;

  std::mutex mutex_;
  std::map<pid_t, Last> last_;
};

} // namespace rsca::process
