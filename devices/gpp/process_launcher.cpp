#include "gpp/process_launcher.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <condition_variable>
#include <cstring>
#include <map>
#include <mutex>
#include <set>
#include <string_view>
#include <system_error>
#include <thread>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/eventfd.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/process_priority.hpp"
#include "gpp/host_info.hpp"

namespace rsca::gpp {
namespace {

using Clock = std::chrono::steady_clock;

// Exited processes list() and wait_for_exit() still know about.
constexpr std::size_t kExitHistory = 256;

// Owns a file descriptor.
class Fd {
public:
  Fd() = default;
  explicit Fd(int fd) : fd_(fd) {}
  Fd(Fd &&other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  Fd &operator=(Fd &&other) noexcept {
    if (this != &other) {
      reset();
      fd_ = std::exchange(other.fd_, -1);
    }
    return *this;
  }
  Fd(const Fd &) = delete;
  Fd &operator=(const Fd &) = delete;
  ~Fd() { reset(); }

  int get() const { return fd_; }
  explicit operator bool() const { return fd_ >= 0; }
  void reset() {
    if (fd_ >= 0) {
      ::close(fd_);
    }
    fd_ = -1;
  }

private:
  int fd_ = -1;
};

// A pidfd (close-on-exec): readable once the process has exited.
Fd open_pidfd(pid_t pid) {
  return Fd{static_cast<int>(::syscall(SYS_pidfd_open, pid, 0))};
}

std::string errno_text(int error) {
  switch (error) {
  case ENOENT:
  case ENOTDIR:
    return "no such file";
  case EACCES:
  case EPERM:
    return "permission denied";
  case ENOEXEC:
    return "not an executable format";
  default:
    return std::generic_category().message(error);
  }
}

std::string signal_name(int signal) {
  const char *abbreviation = ::sigabbrev_np(signal);
  return abbreviation != nullptr ? fmt::format("SIG{}", abbreviation)
                                 : fmt::format("signal {}", signal);
}

tl::unexpected<Error> launch_error(const ExecRequest &request, std::string message) {
  return make_error({request.executable.string(), 0, 0}, "execute", std::move(message));
}

std::string label_of(const ExecRequest &request) {
  return request.label.empty() ? request.executable.filename().string() : request.label;
}

// --- Before spawning: everything that can be checked in this process -------------------------

Expected<void> check_executable(const ExecRequest &request) {
  const auto &path = request.executable;
  if (path.empty()) {
    return launch_error(request, "no executable given");
  }
  struct stat status {};
  if (::stat(path.c_str(), &status) != 0) {
    return launch_error(request,
                        fmt::format("cannot execute {}: {}", path.string(), errno_text(errno)));
  }
  if (S_ISDIR(status.st_mode)) {
    return launch_error(request, fmt::format("cannot execute {}: is a directory", path.string()));
  }
  if (!S_ISREG(status.st_mode)) {
    return launch_error(request,
                        fmt::format("cannot execute {}: not a regular file", path.string()));
  }
  if (::access(path.c_str(), X_OK) != 0) {
    return launch_error(request,
                        fmt::format("cannot execute {}: {}", path.string(), errno_text(errno)));
  }
  return {};
}

Expected<void> check_working_dir(const ExecRequest &request) {
  if (request.working_dir.empty()) {
    return {};
  }
  std::error_code ec;
  if (!std::filesystem::is_directory(request.working_dir, ec)) {
    return launch_error(request, fmt::format("cannot use working directory {}: no such directory",
                                             request.working_dir.string()));
  }
  return {};
}

Expected<void> check_environment(const ExecRequest &request) {
  for (const auto &[name, value] : request.env) {
    if (name.empty() || name.find('=') != std::string::npos) {
      return launch_error(request, fmt::format("invalid environment variable name \"{}\"", name));
    }
  }
  return {};
}

// The log file opened for appending, its directories created; an empty Fd when there is none.
Expected<Fd> open_log(const ExecRequest &request) {
  const auto &path = request.log_file;
  if (path.empty()) {
    return Fd{};
  }
  std::error_code ec;
  if (path.has_parent_path()) {
    std::filesystem::create_directories(path.parent_path(), ec);
  }
  if (ec) {
    return launch_error(request, fmt::format("cannot create the directory of log file {}: {}",
                                             path.string(), ec.message()));
  }
  Fd log{::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC | O_NOCTTY, 0644)};
  if (!log) {
    return launch_error(
        request, fmt::format("cannot open log file {}: {}", path.string(), errno_text(errno)));
  }
  if (log.get() <= STDERR_FILENO) { // this process runs with a standard stream closed
    log = Fd{::fcntl(log.get(), F_DUPFD_CLOEXEC, STDERR_FILENO + 1)};
  }
  return log;
}

// --- Spawning --------------------------------------------------------------------------------

class SpawnActions {
public:
  SpawnActions() { ::posix_spawn_file_actions_init(&actions_); }
  ~SpawnActions() { ::posix_spawn_file_actions_destroy(&actions_); }
  SpawnActions(const SpawnActions &) = delete;
  SpawnActions &operator=(const SpawnActions &) = delete;
  posix_spawn_file_actions_t *get() { return &actions_; }

private:
  posix_spawn_file_actions_t actions_{};
};

class SpawnAttributes {
public:
  SpawnAttributes() { ::posix_spawnattr_init(&attributes_); }
  ~SpawnAttributes() { ::posix_spawnattr_destroy(&attributes_); }
  SpawnAttributes(const SpawnAttributes &) = delete;
  SpawnAttributes &operator=(const SpawnAttributes &) = delete;
  posix_spawnattr_t *get() { return &attributes_; }

private:
  posix_spawnattr_t attributes_{};
};

// stdin from /dev/null, stdout and stderr to the log, the working directory, and no other
// descriptor of this process, whether close-on-exec or not. Returns 0 or an errno value.
int prepare_files(SpawnActions &actions, const ExecRequest &request, int log_fd) {
  int rc =
      ::posix_spawn_file_actions_addopen(actions.get(), STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  if (rc == 0 && log_fd >= 0) {
    rc = ::posix_spawn_file_actions_adddup2(actions.get(), log_fd, STDOUT_FILENO);
  }
  if (rc == 0 && log_fd >= 0) {
    rc = ::posix_spawn_file_actions_adddup2(actions.get(), log_fd, STDERR_FILENO);
  }
  if (rc == 0 && !request.working_dir.empty()) {
    rc = ::posix_spawn_file_actions_addchdir_np(actions.get(), request.working_dir.c_str());
  }
  if (rc == 0) {
    rc = ::posix_spawn_file_actions_addclosefrom_np(actions.get(), STDERR_FILENO + 1);
  }
  return rc;
}

// A process group of its own, no blocked signals, every signal's default action (ignored
// signals would otherwise stay ignored across exec). Returns 0 or an errno value.
int prepare_attributes(SpawnAttributes &attributes) {
  sigset_t none;
  sigset_t all;
  ::sigemptyset(&none);
  ::sigfillset(&all);
  const short flags = POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF;
  int rc = ::posix_spawnattr_setflags(attributes.get(), flags);
  if (rc == 0) {
    rc = ::posix_spawnattr_setpgroup(attributes.get(), 0);
  }
  if (rc == 0) {
    rc = ::posix_spawnattr_setsigmask(attributes.get(), &none);
  }
  if (rc == 0) {
    rc = ::posix_spawnattr_setsigdefault(attributes.get(), &all);
  }
  return rc;
}

std::string_view variable_name(std::string_view entry) {
  return entry.substr(0, entry.find('='));
}

// This process's environment with the request's variables added; the last value of a name wins.
std::vector<std::string> child_environment(const ExecRequest &request) {
  const auto overridden = [&](std::string_view name) {
    return std::any_of(request.env.begin(), request.env.end(),
                       [&](const auto &variable) { return variable.first == name; });
  };
  std::vector<std::string> entries;
  for (char **entry = environ; entry != nullptr && *entry != nullptr; ++entry) {
    if (!overridden(variable_name(*entry))) {
      entries.emplace_back(*entry);
    }
  }
  for (auto it = request.env.begin(); it != request.env.end(); ++it) {
    const auto later = std::find_if(std::next(it), request.env.end(), [&](const auto &variable) {
      return variable.first == it->first;
    });
    if (later == request.env.end()) {
      entries.push_back(it->first + "=" + it->second);
    }
  }
  return entries;
}

std::vector<std::string> child_arguments(const ExecRequest &request) {
  std::vector<std::string> arguments{request.executable.string()};
  arguments.insert(arguments.end(), request.args.begin(), request.args.end());
  return arguments;
}

// The null-terminated array of C strings exec wants; valid while `strings` is.
std::vector<char *> c_strings(std::vector<std::string> &strings) {
  std::vector<char *> pointers;
  pointers.reserve(strings.size() + 1);
  for (auto &string : strings) {
    pointers.push_back(string.data());
  }
  pointers.push_back(nullptr);
  return pointers;
}

// Runs the executable in a new process; exec failures come back from posix_spawn itself (glibc
// reaps the child that failed to exec).
Expected<pid_t> spawn(const ExecRequest &request, int log_fd) {
  SpawnActions actions;
  SpawnAttributes attributes;
  int rc = prepare_files(actions, request, log_fd);
  if (rc == 0) {
    rc = prepare_attributes(attributes);
  }
  if (rc != 0) {
    return launch_error(request, fmt::format("cannot prepare to execute {}: {}",
                                             request.executable.string(), errno_text(rc)));
  }
  auto arguments = child_arguments(request);
  auto environment = child_environment(request);
  auto argv = c_strings(arguments);
  auto envp = c_strings(environment);
  pid_t pid = 0;
  {
    ApplicationPriority as_application; // the node daemon runs above what it starts
    rc = ::posix_spawn(&pid, request.executable.c_str(), actions.get(), attributes.get(),
                       argv.data(), envp.data());
  }
  if (rc != 0) {
    return launch_error(
        request, fmt::format("cannot execute {}: {}", request.executable.string(), errno_text(rc)));
  }
  return pid;
}

// --- Process groups in /proc -----------------------------------------------------------------

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

// --- What the launcher knows about each process ----------------------------------------------

// Another member of a launched process's group, watched once the leader has exited.
struct Member {
  pid_t pid = 0;
  Fd pidfd;
  bool exited = false; // its pidfd fired: no longer polled
};

struct Record {
  std::uint64_t serial = 0; // tells a record from a later one for a reused pid
  ProcessInfo info;
  Fd pidfd;                    // the leader's, until it is reaped
  std::vector<Member> members; // the rest of the group once the leader has exited
  bool terminate_requested = false;
  int last_signal = 0;
  bool leftovers_killed = false;
  bool reported = false;   // on_exit has been called for the leader's exit
  bool group_gone = false; // the leader and every other member are reaped

  bool finished() const { return reported && group_gone; }
};

struct PendingExit {
  pid_t pid = 0;
  std::uint64_t serial = 0;
  ExitStatus status;
};

// One pollfd's owner: a record's leader (member == 0) or another member of its group.
struct Watch {
  pid_t group = 0;
  std::uint64_t serial = 0;
  pid_t member = 0;
};

struct Target {
  pid_t pid = 0;
  std::uint64_t serial = 0;
};

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

ProcessLauncher::ProcessLauncher(ExitCallback on_exit) : state_(std::make_unique<State>()) {
  state_->on_exit = std::move(on_exit);
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
  for (auto *check : {&check_executable, &check_working_dir, &check_environment}) {
    if (auto checked = (*check)(request); !checked) {
      return tl::unexpected(std::move(checked.error()));
    }
  }
  auto log = open_log(request);
  if (!log) {
    return tl::unexpected(std::move(log.error()));
  }
  auto pid = spawn(request, log->get());
  if (!pid) {
    return tl::unexpected(std::move(pid.error()));
  }
  auto pidfd = open_pidfd(*pid);
  if (!pidfd) {
    const int error = errno;
    ::kill(-*pid, SIGKILL);
    ::waitpid(*pid, nullptr, 0);
    return launch_error(request, fmt::format("cannot watch {}: pidfd_open: {}",
                                             request.executable.string(), errno_text(error)));
  }
  Record record;
  record.info = ProcessInfo{.pid = *pid,
                            .label = label_of(request),
                            .executable = request.executable,
                            .started_at = std::chrono::system_clock::now(),
                            .log_file = request.log_file,
                            .running = true,
                            .exit = std::nullopt};
  record.pidfd = std::move(pidfd);
  spdlog::info("{} (pid {}) started: {}", record.info.label, *pid, request.executable.string());
  {
    const std::lock_guard lock(state_->mutex);
    state_->add(std::move(record));
  }
  state_->wake();
  return *pid;
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
