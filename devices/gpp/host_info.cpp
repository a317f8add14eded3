#include "gpp/host_info.hpp"

#include <array>
#include <cerrno>
#include <charconv>

#include <fcntl.h>
#include <sys/utsname.h>
#include <unistd.h>

namespace rsca::gpp {
namespace {

std::string_view trim(std::string_view text) {
  constexpr std::string_view blanks = " \t\r\n";
  const auto first = text.find_first_not_of(blanks);
  if (first == std::string_view::npos) {
    return {};
  }
  const auto last = text.find_last_not_of(blanks);
  return text.substr(first, last - first + 1);
}

// Calls `visit(line)` for each line of `text`.
template <typename Visit>
void for_each_line(std::string_view text, Visit &&visit) {
  while (!text.empty()) {
    const auto end = text.find('\n');
    visit(text.substr(0, end));
    if (end == std::string_view::npos) {
      return;
    }
    text.remove_prefix(end + 1);
  }
}

// Splits "key: value" at the first colon; nullopt when there is none.
std::optional<std::pair<std::string_view, std::string_view>> split_key(std::string_view line) {
  const auto colon = line.find(':');
  if (colon == std::string_view::npos) {
    return std::nullopt;
  }
  return std::pair{trim(line.substr(0, colon)), trim(line.substr(colon + 1))};
}

// Reads the unsigned number at the start of `text` and removes it with the blanks before it.
std::optional<std::uint64_t> take_number(std::string_view &text) {
  text = trim(text);
  std::uint64_t value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc{}) {
    return std::nullopt;
  }
  text.remove_prefix(static_cast<std::size_t>(end - text.data()));
  return value;
}

// A meminfo value, "16318212 kB", in bytes.
std::optional<std::uint64_t> meminfo_bytes(std::string_view value) {
  auto number = take_number(value);
  if (!number) {
    return std::nullopt;
  }
  return trim(value) == "kB" ? *number * 1024 : *number;
}

tl::unexpected<Error> host_error(std::string file, std::string message) {
  return make_error({std::move(file), 0, 0}, "host-info", std::move(message));
}

std::string to_string(const char *text) {
  return text == nullptr ? std::string{} : text;
}

// Closes the descriptor it holds, if any, when it goes.
struct FileDescriptor {
  explicit FileDescriptor(int descriptor) : fd(descriptor) {}
  ~FileDescriptor() {
    if (fd >= 0) {
      ::close(fd);
    }
  }
  FileDescriptor(const FileDescriptor &) = delete;
  FileDescriptor &operator=(const FileDescriptor &) = delete;
  int fd;
};

} // namespace

Expected<MemoryInfo> parse_meminfo(std::string_view text) {
  std::optional<std::uint64_t> total;
  std::optional<std::uint64_t> available;
  std::optional<std::uint64_t> free;
  for_each_line(text, [&](std::string_view line) {
    const auto entry = split_key(line);
    if (!entry) {
      return;
    }
    const auto [key, value] = *entry;
    if (key == "MemTotal") {
      total = meminfo_bytes(value);
    } else if (key == "MemAvailable") {
      available = meminfo_bytes(value);
    } else if (key == "MemFree") {
      free = meminfo_bytes(value);
    }
  });
  if (!total) {
    return host_error("/proc/meminfo", "no MemTotal entry");
  }
  if (!available && !free) {
    return host_error("/proc/meminfo", "neither a MemAvailable nor a MemFree entry");
  }
  return MemoryInfo{*total, available ? *available : *free};
}

unsigned parse_cpuinfo_processors(std::string_view text) {
  unsigned processors = 0;
  for_each_line(text, [&](std::string_view line) {
    const auto entry = split_key(line);
    if (entry && entry->first == "processor") {
      ++processors;
    }
  });
  return processors;
}

Expected<CpuTimes> parse_proc_stat(std::string_view text) {
  std::optional<std::string_view> cpu_line;
  for_each_line(text, [&](std::string_view line) {
    if (!cpu_line && line.starts_with("cpu ")) {
      cpu_line = line.substr(4);
    }
  });
  if (!cpu_line) {
    return host_error("/proc/stat", "no aggregate \"cpu\" line");
  }
  // user nice system idle iowait irq softirq steal [guest guest_nice]: guest time is already
  // counted in user and nice.
  std::array<std::uint64_t, 8> ticks{};
  std::size_t fields = 0;
  auto rest = *cpu_line;
  for (; fields < ticks.size(); ++fields) {
    const auto value = take_number(rest);
    if (!value) {
      break;
    }
    ticks[fields] = *value;
  }
  if (fields < 4) {
    return host_error("/proc/stat", "the \"cpu\" line has fewer than 4 numbers");
  }
  const auto idle = ticks[3] + ticks[4];
  const auto busy = ticks[0] + ticks[1] + ticks[2] + ticks[5] + ticks[6] + ticks[7];
  return CpuTimes{busy, busy + idle};
}

std::optional<double> cpu_utilisation(const CpuTimes &earlier, const CpuTimes &later) {
  if (later.total <= earlier.total || later.busy < earlier.busy) {
    return std::nullopt;
  }
  const auto busy = static_cast<double>(later.busy - earlier.busy);
  const auto total = static_cast<double>(later.total - earlier.total);
  return busy >= total ? 1.0 : busy / total;
}

std::optional<std::string> read_proc_file(const std::filesystem::path &path) {
  const FileDescriptor file{::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY)};
  if (file.fd < 0) {
    return std::nullopt;
  }
  std::string text;
  std::array<char, 4096> buffer{};
  for (;;) {
    const auto n = ::read(file.fd, buffer.data(), buffer.size());
    if (n < 0 && errno == EINTR) {
      continue;
    }
    if (n <= 0) {
      return n == 0 ? std::optional{std::move(text)} : std::nullopt;
    }
    text.append(buffer.data(), static_cast<std::size_t>(n));
  }
}

HostInfo read_host_info() {
  HostInfo host;
  struct utsname names {};
  if (::uname(&names) == 0) {
    host.hostname = to_string(names.nodename);
    host.os_name = to_string(names.sysname);
    host.os_version = to_string(names.release);
    host.processor_name = to_string(names.machine);
  }
  if (const auto cpuinfo = read_proc_file("/proc/cpuinfo")) {
    host.cpu_cores = parse_cpuinfo_processors(*cpuinfo);
  }
  if (host.cpu_cores == 0) {
    const long online = ::sysconf(_SC_NPROCESSORS_ONLN);
    host.cpu_cores = online > 0 ? static_cast<unsigned>(online) : 0;
  }
  if (const auto meminfo = read_proc_file("/proc/meminfo")) {
    if (const auto memory = parse_meminfo(*meminfo)) {
      host.memory_total_bytes = memory->total_bytes;
      host.memory_available_bytes = memory->available_bytes;
    }
  }
  return host;
}

CpuLoadSampler::CpuLoadSampler(std::filesystem::path stat_file)
    : stat_file_(std::move(stat_file)), previous_(read()) {}

std::optional<double> CpuLoadSampler::sample() {
  const auto now = read();
  if (!now) {
    return std::nullopt;
  }
  if (!previous_) {
    previous_ = now;
    return std::nullopt;
  }
  const auto utilisation = cpu_utilisation(*previous_, *now);
  if (now->total != previous_->total) {
    previous_ = now; // also after the counters went back (a processor unplugged): start over
  }
  return utilisation;
}

std::optional<CpuTimes> CpuLoadSampler::read() const {
  const auto text = read_proc_file(stat_file_);
  if (!text) {
    return std::nullopt;
  }
  const auto times = parse_proc_stat(*text);
  return times ? std::optional{*times} : std::nullopt;
}

} // namespace rsca::gpp
