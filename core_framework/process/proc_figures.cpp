#include "process/proc_figures.hpp"

#include <unistd.h>

#include <charconv>
#include <fstream>
#include <iterator>
#include <string>

#include <fmt/format.h>

namespace rsca::process {
namespace {

// The fields of /proc/PID/stat (proc(5)), counted from 1, that are read: all after the command.
constexpr int kUtime = 14;
constexpr int kStime = 15;
constexpr int kThreads = 20;
constexpr int kStartTime = 22;
constexpr int kRss = 24;
constexpr int kFirstAfterCommand = 3;

// Field `number` of the space-separated fields that follow the command's ')'.
std::optional<std::uint64_t> field(std::string_view rest, int number) {
  int at = kFirstAfterCommand;
  std::size_t pos = 0;
  while (pos < rest.size()) {
    while (pos < rest.size() && rest[pos] == ' ')
      ++pos;
    const std::size_t end = std::min(rest.find(' ', pos), rest.size());
    if (at == number) {
      std::uint64_t value = 0;
      const auto token = rest.substr(pos, end - pos);
      // rss may be read as -1 on odd kernels: anything not a plain count is not taken.
      const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
      if (ec != std::errc() || ptr != token.data() + token.size() || token.empty())
        return std::nullopt;
      return value;
    }
    ++at;
    pos = end;
  }
  return std::nullopt;
}

std::optional<std::string> read_text(const std::string &path) {
  std::ifstream in(path);
  if (!in)
    return std::nullopt;
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

long ticks_per_second() {
  static const long hz = ::sysconf(_SC_CLK_TCK);
  return hz > 0 ? hz : 100;
}

std::uint64_t page_bytes() {
  static const long size = ::sysconf(_SC_PAGESIZE);
  return size > 0 ? static_cast<std::uint64_t>(size) : 4096;
}

// Seconds since boot (/proc/uptime), the clock starttime counts on.
std::optional<double> uptime_seconds() {
  auto text = read_text("/proc/uptime");
  if (!text)
    return std::nullopt;
  double seconds = 0;
  if (std::from_chars(text->data(), text->data() + text->size(), seconds).ec != std::errc())
    return std::nullopt;
  return seconds;
}

} // namespace

std::optional<StatLine> parse_stat_line(std::string_view line) {
  const auto close = line.rfind(')');
  if (close == std::string_view::npos || line.find('(') > close)
    return std::nullopt;
  const auto rest = line.substr(close + 1);
  const auto utime = field(rest, kUtime);
  const auto stime = field(rest, kStime);
  const auto threads = field(rest, kThreads);
  const auto start = field(rest, kStartTime);
  const auto rss = field(rest, kRss);
  if (!utime || !stime || !threads || !start || !rss)
    return std::nullopt;
  return StatLine{*utime + *stime, *threads, *start, *rss};
}

double cpu_percent(std::uint64_t ticks_before, std::uint64_t ticks_after,
                   std::chrono::nanoseconds elapsed, long ticks_per_second) {
  if (elapsed.count() <= 0 || ticks_per_second <= 0 || ticks_after < ticks_before)
    return 0;
  const double cpu_seconds =
      static_cast<double>(ticks_after - ticks_before) / static_cast<double>(ticks_per_second);
  return 100.0 * cpu_seconds / std::chrono::duration<double>(elapsed).count();
}

double CpuSampler::since_start(const StatLine &stat) const {
  const auto uptime = uptime_seconds();
  if (!uptime)
    return 0;
  const double started = static_cast<double>(stat.start_ticks) / ticks_per_second();
  return cpu_percent(0, stat.cpu_ticks,
                     std::chrono::duration_cast<std::chrono::nanoseconds>(
                         std::chrono::duration<double>(*uptime - started)),
                     ticks_per_second());
}

std::optional<Figures> CpuSampler::read(pid_t pid) {
  auto text = read_text(fmt::format("/proc/{}/stat", pid));
  if (!text)
    return std::nullopt;
  auto stat = parse_stat_line(*text);
  if (!stat)
    return std::nullopt;
  const Reading now{*stat, std::chrono::steady_clock::now()};
  std::lock_guard lock(mutex_);
  auto it = last_.find(pid);
  // Another process with a reused pid, or the first reading: since the process started.
  if (it == last_.end() || it->second.reading.stat.start_ticks != stat->start_ticks) {
    last_[pid] = {now, since_start(*stat)};
    it = last_.find(pid);
  } else if (now.at - it->second.reading.at >= kMinInterval) {
    it->second.cpu_percent = cpu_percent(it->second.reading.stat.cpu_ticks, stat->cpu_ticks,
                                         now.at - it->second.reading.at, ticks_per_second());
    it->second.reading = now;
  }
  return Figures{it->second.cpu_percent, stat->rss_pages * page_bytes(), stat->threads};
}

} // namespace rsca::process
