// The process groups of launched processes: the members /proc shows for a group, reaping what of
// a group is this process's child (the leader, and members re-parented here since the launcher is
// a child subreaper), watching the rest through pidfds once the leader has exited, killing what a
// leader left behind when it exited on its own, and signalling a group. The reaper thread
// (process_launcher.cpp) calls settle() for each group one of whose pidfds fired.
#include "gpp/process_groups.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <filesystem>
#include <optional>
#include <string_view>
#include <system_error>
#include <utility>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "gpp/host_info.hpp"
#include "process/spawn.hpp"

namespace rsca::gpp::detail {

using process::errno_text;
using process::open_pidfd;

namespace {

struct GroupMember {
  pid_t pid = 0;
  bool dead = false; // a zombie, waiting for its parent to reap it
};

// State and process group from the text of /proc/<pid>/stat: "pid (comm) S ppid pgrp ...".
std::optional<std::pair<char, pid_t>> parse_stat(std::string_view text) {
  const auto paren = text.rfind(')');
  if (paren == std::string_view::npos || paren + 2 >= text.size()) {
    return std::nullopt;
  }
  const char state = text[paren + 2];
  auto rest = text.substr(paren + 3);
  long fields[2] = {0, 0}; // ppid, pgrp
  for (auto &field : fields) {
    rest.remove_prefix(std::min(rest.find_first_not_of(' '), rest.size()));
    const auto [end, ec] = std::from_chars(rest.data(), rest.data() + rest.size(), field);
    if (ec != std::errc{}) {
      return std::nullopt;
    }
    rest.remove_prefix(static_cast<std::size_t>(end - rest.data()));
  }
  return std::pair{state, static_cast<pid_t>(fields[1])};
}

std::optional<pid_t> pid_of(const std::filesystem::path &proc_entry) {
  const auto name = proc_entry.filename().string();
  pid_t pid = 0;
  const auto [end, ec] = std::from_chars(name.data(), name.data() + name.size(), pid);
  if (ec != std::errc{} || end != name.data() + name.size()) {
    return std::nullopt;
  }
  return pid;
}

// The processes whose process group is `group`, as /proc shows them now.
std::vector<GroupMember> scan_group(pid_t group) {
  std::vector<GroupMember> members;
  std::error_code ec;
  for (std::filesystem::directory_iterator it("/proc", ec), end; !ec && it != end;
       it.increment(ec)) {
    const auto pid = pid_of(it->path());
    if (!pid) {
      continue;
    }
    const auto text = read_proc_file(it->path() / "stat");
    const auto stat = text ? parse_stat(*text) : std::nullopt;
    if (stat && stat->second == group) {
      members.push_back({*pid, stat->first == 'Z' || stat->first == 'X'});
    }
  }
  return members;
}

bool group_exists(pid_t group) {
  return ::kill(-group, 0) == 0 || errno == EPERM;
}

ExitStatus exit_status(const siginfo_t &info) {
  ExitStatus status;
  switch (info.si_code) {
  case CLD_EXITED:
    status.kind = ExitStatus::Kind::Exited;
    status.exit_code = info.si_status;
    break;
  case CLD_DUMPED:
    status.core_dumped = true;
    [[fallthrough]];
  case CLD_KILLED:
    status.kind = ExitStatus::Kind::Signalled;
    status.signal = info.si_status;
    break;
  default:
    break;
  }
  return status;
}

} // namespace

std::string signal_name(int signal) {
  const char *abbreviation = ::sigabbrev_np(signal);
  return abbreviation != nullptr ? fmt::format("SIG{}", abbreviation)
                                 : fmt::format("signal {}", signal);
}

// --- Reaping and signalling a group ----------------------------------------------------------

namespace {

void log_exit(const ProcessInfo &info, const ExitStatus &status) {
  const auto level = status.requested || (status.exited() && status.exit_code == 0)
                         ? spdlog::level::info
                         : spdlog::level::warn;
  spdlog::log(level, "{} (pid {}) {}{}", info.label, info.pid, describe(status),
              status.requested ? " after terminate" : "");
}

void record_exit(Record &record, ExitStatus status, std::vector<PendingExit> &exits) {
  status.requested = record.terminate_requested;
  status.terminate_signal = record.last_signal;
  record.info.exit = status;
  record.info.running = false;
  record.pidfd.reset();
  log_exit(record.info, status);
  exits.push_back({record.info.pid, record.serial, status});
}

// Reaps whatever of the group is this process's child: the leader, and members re-parented here.
void reap(Record &record, std::vector<PendingExit> &exits) {
  const pid_t leader = record.info.pid;
  for (;;) {
    siginfo_t info{};
    if (::waitid(P_PGID, static_cast<id_t>(leader), &info, WEXITED | WNOHANG) != 0 ||
        info.si_pid == 0) {
      break;
    }
    if (info.si_pid == leader) {
      record_exit(record, exit_status(info), exits);
    }
  }
  if (!record.info.running) {
    return;
  }
  // A leader that moved to another group, or one something else in this process reaped.
  siginfo_t info{};
  if (::waitid(P_PID, static_cast<id_t>(leader), &info, WEXITED | WNOHANG) == 0) {
    if (info.si_pid == leader) {
      record_exit(record, exit_status(info), exits);
    }
  } else if (errno == ECHILD) {
    record_exit(record, ExitStatus{}, exits);
  }
}

// Watches the members found, keeping the pidfds already open.
void watch_members(Record &record, const std::vector<GroupMember> &found) {
  std::vector<Member> watched;
  for (const auto &process : found) {
    const auto known =
        std::find_if(record.members.begin(), record.members.end(),
                     [&](const Member &member) { return member.pid == process.pid; });
    if (known != record.members.end() && (!known->exited || process.dead)) {
      watched.push_back(std::move(*known));
      continue;
    }
    if (auto pidfd = open_pidfd(process.pid)) { // a dead one's fires at once, and is reaped then
      watched.push_back({process.pid, std::move(pidfd), false});
    }
  }
  record.members = std::move(watched);
}

// A component's group dies with its leader: what is left of it is killed.
void kill_leftovers(Record &record) {
  const bool alive = std::any_of(record.members.begin(), record.members.end(),
                                 [](const Member &member) { return !member.exited; });
  if (!alive || record.terminate_requested || record.leftovers_killed) {
    return;
  }
  spdlog::warn("{} (pid {}) exited leaving processes in its group: killing them", record.info.label,
               record.info.pid);
  ::kill(-record.info.pid, SIGKILL);
  record.leftovers_killed = true;
}

} // namespace

// After a pidfd of the group fired: reaps, then decides whether the group is gone.
void settle(Record &record, std::vector<PendingExit> &exits) {
  for (int attempt = 0; attempt < 3; ++attempt) {
    reap(record, exits);
    if (record.info.running) {
      return; // the leader's children are its own business while it runs
    }
    const auto found = scan_group(record.info.pid);
    if (!found.empty()) {
      watch_members(record, found);
      kill_leftovers(record);
      return;
    }
    record.members.clear();
    if (!group_exists(record.info.pid)) {
      record.group_gone = true;
      return;
    }
    // A process /proc did not show yet (forked while we read it): look again.
  }
  spdlog::warn("process group {} ({}) still exists but /proc shows none of its processes",
               record.info.pid, record.info.label);
  record.group_gone = true;
}

void signal_group(Record &record, int signal) {
  const pid_t pid = record.info.pid;
  record.last_signal = signal;
  spdlog::debug("{}: sending {} to process group {}", record.info.label, signal_name(signal), pid);
  if (::kill(-pid, signal) != 0 && errno != ESRCH) {
    spdlog::warn("{}: cannot send {} to process group {}: {}", record.info.label,
                 signal_name(signal), pid, errno_text(errno));
  }
  if (record.info.running && ::getpgid(pid) != pid) { // the leader left its group
    ::kill(pid, signal);
  }
  if (signal != SIGKILL) { // a stopped process would not act on it
    ::kill(-pid, SIGCONT);
  }
}

} // namespace rsca::gpp::detail
