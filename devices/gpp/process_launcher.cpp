// The GPP's process launcher (gpp/process_launcher.hpp): execute() starts a process through
// process/spawn.hpp (or the starter it was given) in a process group of its own, at the priority
// the node was started with;
// the launcher's state, the reaper thread that polls every pidfd and reports exits, and the
// SIGINT -> SIGTERM -> SIGKILL escalation of terminate(). What is done to a process group when one
// of its pidfds fires or it is signalled is in process_groups.cpp.
#include "gpp/process_launcher.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <condition_variable>
#include <map>
#include <mutex>
#include <set>
#include <system_error>
#include <thread>

#include <poll.h>
#include <signal.h>
#include <sys/eventfd.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/process_priority.hpp"
#include "gpp/process_groups.hpp"
#include "process/spawn.hpp"

namespace rsca::gpp {

using namespace detail;
using process::errno_text;

namespace {

using Clock = std::chrono::steady_clock;

// Exited processes list() and wait_for_exit() still know about.
constexpr std::size_t kExitHistory = 256;

std::string label_of(const ExecRequest &request) {
  return request.label.empty() ? request.program.filename().string() : request.label;
}

Expected<process::Child> spawn_in_own_group(const ExecRequest &request) {
  return process::spawn(request, process::Group::Own);
}

} // namespace

std::string describe(const ExitStatus &status) {
  switch (status.kind) {
  case ExitStatus::Kind::Exited:
    return fmt::format("exited with code {}", status.exit_code);
  case ExitStatus::Kind::Signalled:
    return fmt::format("killed by {}{}", signal_name(status.signal),
                       status.core_dumped ? " (core dumped)" : "");
  case ExitStatus::Kind::Unknown:
    break;
  }
  return "exit status unknown";
}

// --- The launcher's state and reaper ---------------------------------------------------------

struct ProcessLauncher::State {
  ExitCallback on_exit;
  Starter starter;
  mutable std::mutex mutex;
  std::condition_variable changed; // an exit was reported or a group is gone
  std::map<ProcessId, Record> records;
  std::vector<Record> retired; // replaced while their pidfds may be polled: the reaper drops them
  std::uint64_t next_serial = 1;
  bool stopping = false;
  Fd wake_fd;
  std::thread reaper;

  State() : wake_fd(::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK)) {
    if (!wake_fd) {
      throw std::system_error(errno, std::generic_category(), "eventfd");
    }
  }

  void wake() const {
    const std::uint64_t one = 1;
    [[maybe_unused]] const auto written = ::write(wake_fd.get(), &one, sizeof one);
  }

  void drain_wakes() const {
    std::uint64_t count = 0;
    [[maybe_unused]] const auto read = ::read(wake_fd.get(), &count, sizeof count);
  }

  bool on_reaper_thread() const { return std::this_thread::get_id() == reaper.get_id(); }

  Record *find(const Target &target) {
    const auto it = records.find(target.pid);
    return it != records.end() && it->second.serial == target.serial ? &it->second : nullptr;
  }

  bool finished(const Target &target) {
    const auto *record = find(target);
    return record == nullptr || record->finished();
  }

  bool all_finished(const std::vector<Target> &targets) {
    return std::all_of(targets.begin(), targets.end(),
                       [&](const Target &target) { return finished(target); });
  }

  void add(Record record) {
    const auto pid = record.info.pid;
    record.serial = next_serial++;
    if (const auto old = records.find(pid); old != records.end()) {
      if (!old->second.finished()) {
        retired.push_back(std::move(old->second));
      }
      records.erase(old);
    }
    records.emplace(pid, std::move(record));
  }

  // What the reaper polls: the wake eventfd first, then every pidfd not yet fired.
  void collect_watches(std::vector<pollfd> &fds, std::vector<Watch> &watches) const {
    fds.assign(1, pollfd{wake_fd.get(), POLLIN, 0});
    watches.clear();
    for (const auto &[pid, record] : records) {
      if (record.pidfd) {
        fds.push_back({record.pidfd.get(), POLLIN, 0});
        watches.push_back({pid, record.serial, 0});
      }
      for (const auto &member : record.members) {
        if (!member.exited) {
          fds.push_back({member.pidfd.get(), POLLIN, 0});
          watches.push_back({pid, record.serial, member.pid});
        }
      }
    }
  }

  // Handles the pidfds that fired; returns the exits to report.
  std::vector<PendingExit> handle(const std::vector<pollfd> &fds,
                                  const std::vector<Watch> &watches) {
    std::vector<PendingExit> exits;
    std::set<pid_t> groups;
    for (std::size_t i = 1; i < fds.size(); ++i) {
      const auto &watch = watches[i - 1];
      auto *record = fds[i].revents != 0 ? find({watch.group, watch.serial}) : nullptr;
      if (record == nullptr) {
        continue;
      }
      for (auto &member : record->members) {
        member.exited = member.exited || member.pid == watch.member;
      }
      groups.insert(watch.group);
    }
    for (const auto group : groups) {
      settle(records.at(group), exits);
    }
    return exits;
  }

  void report(const std::vector<PendingExit> &exits) {
    for (const auto &exit : exits) {
      call_on_exit(exit);
    }
    {
      const std::lock_guard lock(mutex);
      for (const auto &exit : exits) {
        if (auto *record = find({exit.pid, exit.serial})) {
          record->reported = true;
        }
      }
      forget_old_exits();
    }
    changed.notify_all();
  }

  void call_on_exit(const PendingExit &exit) const {
    if (!on_exit) {
      return;
    }
    try {
      on_exit(exit.pid, exit.status);
    } catch (const std::exception &e) {
      spdlog::error("on_exit for pid {} threw: {}", exit.pid, e.what());
    } catch (...) {
      spdlog::error("on_exit for pid {} threw", exit.pid);
    }
  }

  void forget_old_exits() {
    auto finished_count = static_cast<std::size_t>(std::count_if(
        records.begin(), records.end(), [](const auto &entry) { return entry.second.finished(); }));
    while (finished_count > kExitHistory) {
      auto oldest = records.end();
      for (auto it = records.begin(); it != records.end(); ++it) {
        if (it->second.finished() &&
            (oldest == records.end() || it->second.serial < oldest->second.serial)) {
          oldest = it;
        }
      }
      records.erase(oldest);
      --finished_count;
    }
  }

  void run() {
    std::vector<pollfd> fds;
    std::vector<Watch> watches;
    for (;;) {
      {
        const std::lock_guard lock(mutex);
        retired.clear();
        if (stopping) {
          return;
        }
        collect_watches(fds, watches);
      }
      if (::poll(fds.data(), fds.size(), -1) < 0) {
        if (errno != EINTR) {
          spdlog::error("process reaper: poll failed: {}", errno_text(errno));
        }
        continue;
      }
      drain_wakes();
      std::vector<PendingExit> exits;
      {
        const std::lock_guard lock(mutex);
        exits = handle(fds, watches);
      }
      report(exits);
    }
  }

  // The escalation for `targets`, with the lock held except while waiting.
  Expected<void> stop(std::unique_lock<std::mutex> &lock, const std::vector<Target> &targets,
                      const TerminateOptions &options) {
    for (const auto &target : targets) {
      if (auto *record = find(target)) {
        record->terminate_requested = true;
      }
    }
    const std::array<std::pair<int, std::chrono::milliseconds>, 3> stages{
        {{SIGINT, options.grace_sigint},
         {SIGTERM, options.grace_sigterm},
         {SIGKILL, options.grace_sigkill}}};
    for (const auto &[signal, grace] : stages) {
      if (all_finished(targets)) {
        return {};
      }
      for (const auto &target : targets) {
        if (auto *record = find(target); record != nullptr && !record->group_gone) {
          signal_group(*record, signal);
        }
      }
      changed.wait_until(lock, Clock::now() + grace, [&] { return all_finished(targets); });
    }
    if (all_finished(targets)) {
      return {};
    }
    return still_running_error(targets);
  }

  tl::unexpected<Error> still_running_error(const std::vector<Target> &targets) {
    std::string names;
    for (const auto &target : targets) {
      if (const auto *record = find(target); record != nullptr && !record->finished()) {
        names += fmt::format("{}{} (pid {})", names.empty() ? "" : ", ", record->info.label,
                             record->info.pid);
      }
    }
    return make_error({"gpp", 0, 0}, "terminate",
                      fmt::format("still running after SIGKILL: {}", names));
  }
};

// --- ProcessLauncher -------------------------------------------------------------------------

ProcessLauncher::ProcessLauncher(ExitCallback on_exit, Starter starter)
    : state_(std::make_unique<State>()) {
  state_->on_exit = std::move(on_exit);
  state_->starter = starter ? std::move(starter) : Starter(spawn_in_own_group);
  if (::prctl(PR_SET_CHILD_SUBREAPER, 1) != 0) {
    spdlog::warn("process launcher: cannot become a child subreaper: {}", errno_text(errno));
  }
  state_->reaper = std::thread([state = state_.get()] { state->run(); });
}

ProcessLauncher::~ProcessLauncher() {
  if (auto stopped = terminate_all(); !stopped) {
    spdlog::error("process launcher: {}", stopped.error().to_string());
  }
  {
    const std::lock_guard lock(state_->mutex);
    state_->stopping = true;
  }
  state_->wake();
  state_->reaper.join();
}

Expected<ProcessId> ProcessLauncher::execute(const ExecRequest &request) {
  auto child = [&] {
    // The node runs above what it starts: the process starts at the node's starting priority.
    ApplicationPriority as_application;
    return state_->starter(request);
  }();
  if (!child) {
    return tl::unexpected(std::move(child.error()));
  }
  const auto pid = child->pid;
  Record record;
  record.info = ProcessInfo{.pid = pid,
                            .label = label_of(request),
                            .executable = request.program,
                            .started_at = std::chrono::system_clock::now(),
                            .log_file = request.log_file,
                            .running = true,
                            .exit = std::nullopt};
  record.pidfd = std::move(child->pidfd);
  spdlog::info("{} (pid {}) started: {}", record.info.label, pid, request.program.string());
  {
    const std::lock_guard lock(state_->mutex);
    state_->add(std::move(record));
  }
  state_->wake();
  return pid;
}

Expected<void> ProcessLauncher::terminate(ProcessId pid, TerminateOptions options) {
  if (state_->on_reaper_thread()) {
    return make_error({"gpp", 0, 0}, "terminate", "terminate() called from on_exit");
  }
  std::unique_lock lock(state_->mutex);
  const auto it = state_->records.find(pid);
  if (it == state_->records.end()) {
    return make_error({"gpp", 0, 0}, "terminate",
                      fmt::format("no process {} was launched here", pid));
  }
  return state_->stop(lock, {Target{pid, it->second.serial}}, options);
}

Expected<void> ProcessLauncher::terminate_all(TerminateOptions options) {
  if (state_->on_reaper_thread()) {
    return make_error({"gpp", 0, 0}, "terminate", "terminate_all() called from on_exit");
  }
  std::unique_lock lock(state_->mutex);
  std::vector<Target> targets;
  for (const auto &[pid, record] : state_->records) {
    if (!record.finished()) {
      targets.push_back({pid, record.serial});
    }
  }
  return state_->stop(lock, targets, options);
}

std::vector<ProcessInfo> ProcessLauncher::list() const {
  const std::lock_guard lock(state_->mutex);
  std::vector<const Record *> records;
  for (const auto &entry : state_->records) {
    records.push_back(&entry.second);
  }
  std::sort(records.begin(), records.end(),
            [](const Record *a, const Record *b) { return a->serial < b->serial; });
  std::vector<ProcessInfo> infos;
  infos.reserve(records.size());
  for (const auto *record : records) {
    infos.push_back(record->info);
  }
  return infos;
}

bool ProcessLauncher::running(ProcessId pid) const {
  const std::lock_guard lock(state_->mutex);
  const auto it = state_->records.find(pid);
  return it != state_->records.end() && it->second.info.running;
}

std::optional<ExitStatus> ProcessLauncher::wait_for_exit(ProcessId pid,
                                                         std::chrono::milliseconds timeout) {
  if (state_->on_reaper_thread()) {
    return std::nullopt;
  }
  std::unique_lock lock(state_->mutex);
  const auto it = state_->records.find(pid);
  if (it == state_->records.end()) {
    return std::nullopt;
  }
  const Target target{pid, it->second.serial};
  state_->changed.wait_for(lock, timeout, [&] {
    const auto *record = state_->find(target);
    return record == nullptr || record->reported;
  });
  const auto *record = state_->find(target);
  return record != nullptr && record->reported ? record->info.exit : std::nullopt;
}

} // namespace rsca::gpp
