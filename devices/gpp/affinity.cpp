#include "affinity.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <sched.h>
#include <sys/resource.h>

#include "common/cpu_list.hpp"

namespace rsca::gpp {
namespace {

namespace fs = std::filesystem;

tl::unexpected<Error> affinity_error(std::string message) {
  return make_error({"affinity", 0, 0}, "affinity", std::move(message));
}

// A /sys file that holds one CPU list, or why it cannot be read.
tl::expected<std::vector<unsigned>, std::string> read_cpu_list(const fs::path &file) {
  std::ifstream in(file);
  std::string text;
  if (!in || !std::getline(in, text))
    return tl::unexpected(fmt::format("{} cannot be read", file.string()));
  return parse_cpu_list(text);
}

Expected<std::vector<unsigned>> online_cpus(const std::string &sys) {
  auto online = read_cpu_list(fs::path(sys) / "devices/system/cpu/online");
  if (!online)
    return affinity_error(fmt::format("this host's CPUs: {}", online.error()));
  return *online;
}

// Every CPU of `cpus` must be one this node may use.
Expected<std::vector<unsigned>> within(std::vector<unsigned> cpus,
                                       const std::vector<unsigned> &usable) {
  for (unsigned cpu : cpus)
    if (!std::binary_search(usable.begin(), usable.end(), cpu))
      return affinity_error(fmt::format("cpu {} is not one this node may use (it may use {})", cpu,
                                        fmt::join(usable, ",")));
  return cpus;
}

Expected<std::vector<unsigned>> cpus_of_list(const std::string &value, const std::string &sys) {
  auto wanted = parse_cpu_list(value);
  if (!wanted)
    return affinity_error(fmt::format("cpu \"{}\": {}", value, wanted.error()));
  auto online = online_cpus(sys);
  if (!online)
    return online;
  for (unsigned cpu : *wanted)
    if (!std::binary_search(online->begin(), online->end(), cpu))
      return affinity_error(fmt::format("cpu {} is not online on this host (online: {})", cpu,
                                        fmt::join(*online, ",")));
  return *wanted;
}

Expected<std::vector<unsigned>> cpus_of_nodes(const std::string &value, const std::string &sys) {
  auto nodes = parse_cpu_list(value);
  if (!nodes)
    return affinity_error(fmt::format("socket \"{}\": {}", value, nodes.error()));
  std::vector<unsigned> cpus;
  for (unsigned node : *nodes) {
    auto list =
        read_cpu_list(fs::path(sys) / fmt::format("devices/system/node/node{}/cpulist", node));
    if (!list)
      return affinity_error(fmt::format("NUMA node {} is not on this host", node));
    cpus.insert(cpus.end(), list->begin(), list->end());
  }
  std::sort(cpus.begin(), cpus.end());
  cpus.erase(std::unique(cpus.begin(), cpus.end()), cpus.end());
  if (cpus.empty())
    return affinity_error(fmt::format("NUMA nodes {} have no CPUs", value));
  return cpus;
}

// An interface name as the kernel allows it, so that it cannot name another /sys path.
bool is_interface_name(const std::string &name) {
  return !name.empty() && name.size() <= 15 && name != "." && name != ".." &&
         std::all_of(name.begin(), name.end(), [](unsigned char c) {
           return std::isalnum(c) || c == '_' || c == '-' || c == '.' || c == '@' || c == ':';
         });
}

// The CPUs near the interface's device (its local_cpulist). A virtual interface (loopback, veth)
// has no device, and so no CPUs of its own to run near.
Expected<std::vector<unsigned>> cpus_of_nic(const std::string &nic, const std::string &sys) {
  if (!is_interface_name(nic))
    return affinity_error(fmt::format("nic \"{}\" is not a network interface name", nic));
  const fs::path dir = fs::path(sys) / "class/net" / nic;
  std::error_code ec;
  if (!fs::exists(dir, ec))
    return affinity_error(fmt::format("nic {} is not on this host", nic));
  auto list = read_cpu_list(dir / "device/local_cpulist");
  if (!list)
    return affinity_error(
        fmt::format("nic {} has no device whose CPUs could be used (a virtual interface?)", nic));
  return *list;
}

Expected<int> nice_of(const std::string &value) {
  int nice = 0;
  const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), nice);
  if (ec != std::errc() || end != value.data() + value.size() || nice < -20 || nice > 19)
    return affinity_error(fmt::format("nice \"{}\" is not a nice value (-20 to 19)", value));
  return nice;
}

} // namespace

std::vector<unsigned> usable_cpus() {
  std::vector<unsigned> out;
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof(set), &set) != 0)
    return out;
  for (unsigned cpu = 0; cpu < CPU_SETSIZE; ++cpu)
    if (CPU_ISSET(cpu, &set))
      out.push_back(cpu);
  return out;
}

Expected<ProcessPlacement> resolve_affinity(const protocol::node::AffinityDirective &directive,
                                            const std::string &sys,
                                            const std::vector<unsigned> &usable) {
  if (directive.value.size() > protocol::node::AffinityDirective::kMaxValue)
    return affinity_error("the affinity value is too long");
  ProcessPlacement placement;
  Expected<std::vector<unsigned>> cpus = std::vector<unsigned>{};
  if (directive.directive == "cpu")
    cpus = cpus_of_list(directive.value, sys);
  else if (directive.directive == "socket")
    cpus = cpus_of_nodes(directive.value, sys);
  else if (directive.directive == "nic")
    cpus = cpus_of_nic(directive.value, sys);
  else if (directive.directive == "nice") {
    auto nice = nice_of(directive.value);
    if (!nice)
      return tl::unexpected(nice.error());
    placement.nice = *nice;
  } else
    return affinity_error(fmt::format("affinity class \"{}\" is none of cpu, socket, nic, nice",
                                      directive.directive));
  if (!cpus)
    return tl::unexpected(cpus.error());
  auto allowed = within(std::move(*cpus), usable);
  if (!allowed)
    return tl::unexpected(allowed.error());
  placement.cpus = std::move(*allowed);
  return placement;
}

ScopedThreadCpus::ScopedThreadCpus(const std::vector<unsigned> &cpus) {
  if (cpus.empty() || sched_getaffinity(0, sizeof(saved_), &saved_) != 0)
    return;
  cpu_set_t set;
  CPU_ZERO(&set);
  for (unsigned cpu : cpus)
    CPU_SET(cpu, &set); // below CPU_SETSIZE: kMaxCpuIndex bounds every list
  pinned_ = sched_setaffinity(0, sizeof(set), &set) == 0;
}

ScopedThreadCpus::~ScopedThreadCpus() {
  if (pinned_)
    sched_setaffinity(0, sizeof(saved_), &saved_);
}

Expected<void> apply_nice(pid_t pid, const ProcessPlacement &placement) {
  if (!placement.nice)
    return {};
  std::error_code ec;
  for (const auto &task : fs::directory_iterator(fmt::format("/proc/{}/task", pid), ec)) {
    const pid_t tid = std::stoi(task.path().filename().string());
    if (setpriority(PRIO_PROCESS, static_cast<id_t>(tid), *placement.nice) != 0 && errno != ESRCH)
      return affinity_error(
          fmt::format("cannot set nice {} of {}: {}", *placement.nice, pid, std::strerror(errno)));
  }
  // No /proc/<pid>/task: the process is gone already; its exit is reported as any exit.
  if (ec && ec != std::errc::no_such_file_or_directory)
    return affinity_error(fmt::format("process {}: {}", pid, ec.message()));
  return {};
}

} // namespace rsca::gpp
