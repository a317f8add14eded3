// rsca-bench-raw discovery (raw_discovery.hpp): N bare participants forked at once.
#include "raw_discovery.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <set>
#include <vector>

#include "../bench_common.hpp"
#include "dds/participant.hpp"

namespace rsca::bench::raw {

namespace {

using rsca::bench::mono_ns;

constexpr std::uint32_t kBatch = 32;

// One participant of `discovery`, in a process of its own, joined as a component process joins
// (the project's configuration with the component lease): it writes on `report` when it has seen
// `participants` of them (itself included, and those already there before it: --existing), the
// nanoseconds since `started`, then waits for SIGTERM.
[[noreturn]] void discovery_member(std::size_t participants, std::uint64_t started, int report,
                                   const std::atomic<bool> &stop) {
  auto participant =
      rsca::dds::Participant::create(rsca::dds::DdsSettings::from_environment().for_component());
  if (!participant)
    _exit(1);
  const dds_entity_t reader =
      dds_create_reader((*participant)->get(), DDS_BUILTIN_TOPIC_DCPSPARTICIPANT, nullptr, nullptr);
  const dds_entity_t waitset = dds_create_waitset((*participant)->get());
  const dds_entity_t fresh = dds_create_readcondition(reader, DDS_NOT_READ_SAMPLE_STATE);
  if (reader < 0 || waitset < 0 || fresh < 0 || dds_waitset_attach(waitset, fresh, reader) < 0)
    _exit(1);
  std::set<dds_instance_handle_t> seen;
  while (!stop && seen.size() < participants) {
    dds_waitset_wait(waitset, nullptr, 0, DDS_MSECS(100));
    void *samples[kBatch] = {nullptr};
    dds_sample_info_t infos[kBatch];
    const dds_return_t n =
        dds_read_mask(reader, samples, infos, kBatch, kBatch, DDS_NOT_READ_SAMPLE_STATE);
    for (dds_return_t i = 0; i < n; ++i)
      seen.insert(infos[i].instance_handle);
    if (n > 0)
      dds_return_loan(reader, samples, n);
  }
  if (seen.size() >= participants) {
    const std::uint64_t elapsed = mono_ns() - started;
    if (write(report, &elapsed, sizeof elapsed) != sizeof elapsed)
      _exit(1);
  }
  while (!stop)
    pause();
  participant->reset();
  _exit(0);
}

// The reports of the members, until all have reported or `timeout_ms` has passed.
std::vector<std::uint64_t> read_reports(int from, std::size_t expected, std::uint64_t timeout_ms) {
  std::vector<std::uint64_t> settled;
  const std::uint64_t deadline = mono_ns() + timeout_ms * 1'000'000u;
  while (settled.size() < expected) {
    const std::uint64_t now = mono_ns();
    if (now >= deadline)
      break;
    pollfd ready{from, POLLIN, 0};
    if (poll(&ready, 1, static_cast<int>((deadline - now) / 1'000'000u) + 1) <= 0)
      continue;
    std::uint64_t elapsed = 0;
    if (read(from, &elapsed, sizeof elapsed) != sizeof elapsed)
      break; // every member has gone
    settled.push_back(elapsed);
  }
  return settled;
}

} // namespace

int discovery(std::size_t participants, std::size_t existing, std::uint64_t timeout_ms,
              const std::atomic<bool> &stop) {
  int report[2];
  if (pipe2(report, O_CLOEXEC) != 0) {
    std::fprintf(stderr, "rsca-bench-raw discovery: cannot make a pipe\n");
    return 2;
  }
  const std::uint64_t started = mono_ns();
  std::vector<pid_t> members;
  for (std::size_t i = 0; i < participants; ++i) {
    const pid_t pid = fork();
    if (pid == 0) {
      close(report[0]);
      discovery_member(participants + existing, started, report[1], stop);
    }
    if (pid < 0)
      break;
    members.push_back(pid);
  }
  close(report[1]);
  auto settled = read_reports(report[0], members.size(), timeout_ms);
  for (pid_t pid : members)
    kill(pid, SIGTERM);
  for (pid_t pid : members)
    waitpid(pid, nullptr, 0);
  close(report[0]);
  std::sort(settled.begin(), settled.end());
  auto ms = [](std::uint64_t ns) { return static_cast<double>(ns) / 1e6; };
  std::printf("{\"participants\": %zu, \"started\": %zu, \"settled\": %zu, \"timeout_ms\": %llu",
              participants, members.size(), settled.size(),
              static_cast<unsigned long long>(timeout_ms));
  if (!settled.empty())
    std::printf(", \"settled_median_ms\": %.1f, \"settled_max_ms\": %.1f",
                ms(settled[settled.size() / 2]), ms(settled.back()));
  std::printf("}\n");
  return settled.size() == participants ? 0 : 1;
}

} // namespace rsca::bench::raw
