// process/spawn.hpp: the checks made before anything starts, the child's descriptors, signals,
// group and environment as posix_spawn actions and attributes, and the pidfd that watches it.
#include "process/spawn.hpp"

#include <algorithm>
#include <cerrno>
#include <string_view>
#include <system_error>
#include <thread>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

namespace rsca::process {
namespace {

tl::unexpected<Error> spawn_error(const Command &command, std::string message) {
  return make_error({command.program.string(), 0, 0}, "execute", std::move(message));
}

// --- Before spawning: everything that can be checked in this process -------------------------

Expected<void> check_executable(const Command &command) {
  const auto &path = command.program;
  if (path.empty()) {
    return spawn_error(command, "no executable given");
  }
  struct stat status {};
  if (::stat(path.c_str(), &status) != 0) {
    return spawn_error(command,
                       fmt::format("cannot execute {}: {}", path.string(), errno_text(errno)));
  }
  if (S_ISDIR(status.st_mode)) {
    return spawn_error(command, fmt::format("cannot execute {}: is a directory", path.string()));
  }
  if (!S_ISREG(status.st_mode)) {
    return spawn_error(command,
                       fmt::format("cannot execute {}: not a regular file", path.string()));
  }
  if (::access(path.c_str(), X_OK) != 0) {
    return spawn_error(command,
                       fmt::format("cannot execute {}: {}", path.string(), errno_text(errno)));
  }
  return {};
}

Expected<void> check_working_dir(const Command &command) {
  if (command.working_dir.empty()) {
    return {};
  }
  std::error_code ec;
  if (!std::filesystem::is_directory(command.working_dir, ec)) {
    return spawn_error(command, fmt::format("cannot use working directory {}: no such directory",
                                            command.working_dir.string()));
  }
  return {};
}

Expected<void> check_environment(const Command &command) {
  for (const auto &[name, value] : command.env) {
    if (name.empty() || name.find('=') != std::string::npos) {
      return spawn_error(command, fmt::format("invalid environment variable name \"{}\"", name));
    }
  }
  return {};
}

// The log file opened for appending, its directories created; an empty Fd when there is none.
Expected<Fd> open_log(const Command &command) {
  const auto &path = command.log_file;
  if (path.empty()) {
    return Fd{};
  }
  std::error_code ec;
  if (path.has_parent_path()) {
    std::filesystem::create_directories(path.parent_path(), ec);
  }
  if (ec) {
    return spawn_error(command, fmt::format("cannot create the directory of log file {}: {}",
                                            path.string(), ec.message()));
  }
  Fd log{::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC | O_NOCTTY, 0644)};
  if (!log) {
    return spawn_error(
        command, fmt::format("cannot open log file {}: {}", path.string(), errno_text(errno)));
  }
  if (log.get() <= STDERR_FILENO) { // this process runs with a standard stream closed
    log = Fd{::fcntl(log.get(), F_DUPFD_CLOEXEC, STDERR_FILENO + 1)};
  }
  return log;
}

// Above the numbers a child is given descriptors as (Command::inherit).
constexpr int kFirstCopiedFd = 64;

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

// stdin from /dev/null, stdout and stderr to the log, the working directory, the one descriptor
// the command hands over, and no other descriptor of this process, close-on-exec or not. Returns 0
// or an errno value.
int prepare_files(SpawnActions &actions, const Command &command, int log_fd,
                  const std::vector<Fd> &inherited) {
  int rc =
      ::posix_spawn_file_actions_addopen(actions.get(), STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  if (rc == 0 && log_fd >= 0) {
    rc = ::posix_spawn_file_actions_adddup2(actions.get(), log_fd, STDOUT_FILENO);
  }
  if (rc == 0 && log_fd >= 0) {
    rc = ::posix_spawn_file_actions_adddup2(actions.get(), log_fd, STDERR_FILENO);
  }
  if (rc == 0 && !command.working_dir.empty()) {
    rc = ::posix_spawn_file_actions_addchdir_np(actions.get(), command.working_dir.c_str());
  }
  int first_closed = STDERR_FILENO + 1;
  for (std::size_t i = 0; rc == 0 && i < command.inherit.size(); ++i) {
    rc = ::posix_spawn_file_actions_adddup2(actions.get(), inherited[i].get(),
                                            command.inherit[i].as);
    first_closed = std::max(first_closed, command.inherit[i].as + 1);
  }
  if (rc == 0) {
    rc = ::posix_spawn_file_actions_addclosefrom_np(actions.get(), first_closed);
  }
  return rc;
}

// The flag that puts the child where `group` says.
short group_flag(Group group) {
  switch (group) {
  case Group::Own:
    return POSIX_SPAWN_SETPGROUP;
  case Group::Session:
    return POSIX_SPAWN_SETSID;
  case Group::Caller:
    break;
  }
  return 0;
}

// The process group or session asked for, no blocked signals, every signal's default action
// (ignored signals would otherwise stay ignored across exec). Returns 0 or an errno value.
int prepare_attributes(SpawnAttributes &attributes, Group group) {
  sigset_t none;
  sigset_t all;
  ::sigemptyset(&none);
  ::sigfillset(&all);
  const auto flags =
      static_cast<short>(group_flag(group) | POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
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

// This process's environment with the command's variables added; the last value of a name wins.
std::vector<std::string> child_environment(const Command &command) {
  const auto overridden = [&](std::string_view name) {
    return std::any_of(command.env.begin(), command.env.end(),
                       [&](const auto &variable) { return variable.first == name; });
  };
  std::vector<std::string> entries;
  for (char **entry = environ; entry != nullptr && *entry != nullptr; ++entry) {
    if (!overridden(variable_name(*entry))) {
      entries.emplace_back(*entry);
    }
  }
  for (auto it = command.env.begin(); it != command.env.end(); ++it) {
    const auto later = std::find_if(std::next(it), command.env.end(), [&](const auto &variable) {
      return variable.first == it->first;
    });
    if (later == command.env.end()) {
      entries.push_back(it->first + "=" + it->second);
    }
  }
  return entries;
}

std::vector<std::string> child_arguments(const Command &command) {
  std::vector<std::string> arguments{command.program.string()};
  arguments.insert(arguments.end(), command.args.begin(), command.args.end());
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

// Runs the program in a new process; exec failures come back from posix_spawn itself (glibc
// reaps the child that failed to exec).
Expected<pid_t> start(const Command &command, Group group, int log_fd) {
  SpawnActions actions;
  SpawnAttributes attributes;
  // Each inherited descriptor is first copied above every number it is given as, so that giving
  // one its number cannot overwrite another not given yet.
  std::vector<Fd> inherited;
  for (const auto &i : command.inherit) {
    inherited.emplace_back(::fcntl(i.fd, F_DUPFD_CLOEXEC, kFirstCopiedFd));
    if (!inherited.back())
      return spawn_error(command, fmt::format("cannot hand descriptor {} to {}: {}", i.fd,
                                              command.program.string(), errno_text(errno)));
  }
  int rc = prepare_files(actions, command, log_fd, inherited);
  if (rc == 0) {
    rc = prepare_attributes(attributes, group);
  }
  if (rc != 0) {
    return spawn_error(command, fmt::format("cannot prepare to execute {}: {}",
                                            command.program.string(), errno_text(rc)));
  }
  auto arguments = child_arguments(command);
  auto environment = child_environment(command);
  auto argv = c_strings(arguments);
  auto envp = c_strings(environment);
  pid_t pid = 0;
  rc = ::posix_spawn(&pid, command.program.c_str(), actions.get(), attributes.get(), argv.data(),
                     envp.data());
  // ETXTBSY: a file this process has just written (a node's package) is still open for writing
  // in a child another thread cloned while it was being written, until that child closes its
  // descriptors on its way to exec: a few milliseconds at most on a loaded host. Seen in CI: two
  // packages fetched at once, one executed while the other's child was starting.
  for (int delay_ms = 1; rc == ETXTBSY && delay_ms <= 64; delay_ms *= 2) {
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    rc = ::posix_spawn(&pid, command.program.c_str(), actions.get(), attributes.get(), argv.data(),
                       envp.data());
  }
  if (rc != 0) {
    return spawn_error(
        command, fmt::format("cannot execute {}: {}", command.program.string(), errno_text(rc)));
  }
  return pid;
}

// A child that cannot be watched is not kept: it is killed, with its group if it leads one, and
// reaped.
void kill_and_reap(pid_t pid, Group group) {
  ::kill(group == Group::Caller ? pid : -pid, SIGKILL);
  ::waitpid(pid, nullptr, 0);
}

} // namespace

Expected<Fd> prepare_to_spawn(const Command &command) {
  for (auto *check : {&check_executable, &check_working_dir, &check_environment}) {
    if (auto checked = (*check)(command); !checked) {
      return tl::unexpected(std::move(checked.error()));
    }
  }
  return open_log(command);
}

Expected<Child> spawn(const Command &command, Group group) {
  auto log = prepare_to_spawn(command);
  if (!log) {
    return tl::unexpected(std::move(log.error()));
  }
  auto pid = start(command, group, log->get());
  if (!pid) {
    return tl::unexpected(std::move(pid.error()));
  }
  Child child{*pid, open_pidfd(*pid)};
  if (!child.pidfd) {
    const int error = errno;
    kill_and_reap(*pid, group);
    return spawn_error(command, fmt::format("cannot watch {}: pidfd_open: {}",
                                            command.program.string(), errno_text(error)));
  }
  return child;
}

// glibc's <sys/pidfd.h> lacks extern "C" in this version: the system call directly.
Fd open_pidfd(pid_t pid) {
  return Fd{static_cast<int>(::syscall(SYS_pidfd_open, pid, 0))};
}

bool wait_exited(const Fd &pidfd, std::chrono::milliseconds timeout) {
  pollfd ready{pidfd.get(), POLLIN, 0};
  return ::poll(&ready, 1, static_cast<int>(timeout.count())) == 1;
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

} // namespace rsca::process
