// process/spawn.hpp: the checks made before anything starts, the child's descriptors, signals,
// group and environment as posix_spawn actions and attributes, and the pidfd that watches it.
#include "process/spawn.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <string_view>
#include <system_error>
#include <thread>
#include <variant>

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

// The lowest number a child's descriptors are copied to before it is given them: above every
// number it is given one as (Command::inherit), so that giving one its number cannot overwrite
// another not given yet. Not a fixed number: under a low descriptor limit (64) there is no
// descriptor above a fixed 64, and every launch failed.
int first_free_number(const Command &command) {
  int above = STDERR_FILENO + 1;
  for (const auto &i : command.inherit) {
    above = std::max(above, i.as + 1);
  }
  return above;
}

// Whether the child is given a descriptor as `fd` (Command::inherit).
bool given_as(const std::vector<Command::Inherited> &inherit, int fd) {
  return std::any_of(inherit.begin(), inherit.end(),
                     [fd](const Command::Inherited &i) { return i.as == fd; });
}

// A copy of `fd` at `above` or higher, close-on-exec; an empty Fd on failure (errno says why).
Fd copy_above(int fd, int above) {
  return Fd{::fcntl(fd, F_DUPFD_CLOEXEC, above)};
}

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
  for (std::size_t i = 0; rc == 0 && i < command.inherit.size(); ++i) {
    rc = ::posix_spawn_file_actions_adddup2(actions.get(), inherited[i].get(),
                                            command.inherit[i].as);
  }
  // Between stderr and the numbers given, those not given are closed too (an open one is not
  // an error: glibc ignores a descriptor that is not open).
  for (int fd = STDERR_FILENO + 1; rc == 0 && fd < first_free_number(command); ++fd) {
    if (!given_as(command.inherit, fd)) {
      rc = ::posix_spawn_file_actions_addclose(actions.get(), fd);
    }
  }
  if (rc == 0) {
    rc = ::posix_spawn_file_actions_addclosefrom_np(actions.get(), first_free_number(command));
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

// Each inherited descriptor copied above every number a descriptor is given as.
Expected<std::vector<Fd>> copy_inherited(const Command &command) {
  std::vector<Fd> inherited;
  for (const auto &i : command.inherit) {
    inherited.push_back(copy_above(i.fd, first_free_number(command)));
    if (!inherited.back())
      return spawn_error(command, fmt::format("cannot hand descriptor {} to {}: {}", i.fd,
                                              command.program.string(), errno_text(errno)));
  }
  return inherited;
}

// The child's argv and envp, and the strings they point into (neither copied nor moved).
struct ExecStrings {
  explicit ExecStrings(const Command &command)
      : arguments(child_arguments(command)), environment(child_environment(command)),
        argv(c_strings(arguments)), envp(c_strings(environment)) {}
  ExecStrings(const ExecStrings &) = delete;
  ExecStrings &operator=(const ExecStrings &) = delete;
  std::vector<std::string> arguments;
  std::vector<std::string> environment;
  std::vector<char *> argv;
  std::vector<char *> envp;
};

// Runs the program in a new process; exec failures come back from posix_spawn itself (glibc
// reaps the child that failed to exec).
Expected<pid_t> start(const Command &command, Group group, int log_fd) {
  SpawnActions actions;
  SpawnAttributes attributes;
  auto copies = copy_inherited(command);
  if (!copies) {
    return tl::unexpected(std::move(copies.error()));
  }
  const auto &inherited = *copies;
  int rc = prepare_files(actions, command, log_fd, inherited);
  if (rc == 0) {
    rc = prepare_attributes(attributes, group);
  }
  if (rc != 0) {
    return spawn_error(command, fmt::format("cannot prepare to execute {}: {}",
                                            command.program.string(), errno_text(rc)));
  }
  ExecStrings strings(command);
  pid_t pid = 0;
  rc = ::posix_spawn(&pid, command.program.c_str(), actions.get(), attributes.get(),
                     strings.argv.data(), strings.envp.data());
  // ETXTBSY: a file this process has just written (a node's package) is still open for writing
  // in a child another thread cloned while it was being written, until that child closes its
  // descriptors on its way to exec: a few milliseconds at most on a loaded host. Seen in CI: two
  // packages fetched at once, one executed while the other's child was starting.
  for (int delay_ms = 1; rc == ETXTBSY && delay_ms <= 64; delay_ms *= 2) {
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    rc = ::posix_spawn(&pid, command.program.c_str(), actions.get(), attributes.get(),
                       strings.argv.data(), strings.envp.data());
  }
  if (rc != 0) {
    return spawn_error(
        command, fmt::format("cannot execute {}: {}", command.program.string(), errno_text(rc)));
  }
  return pid;
}

// --- A child that changes user: forked, and only system calls until it executes ----------------

// What the forked child needs, all made before the fork: the child must not allocate or take a
// lock (another thread of this process may have held one as it forked).
struct ForkPlan {
  const char *program = nullptr;
  char *const *argv = nullptr;
  char *const *envp = nullptr;
  const char *working_dir = nullptr; // null: this process's
  int null_fd = -1;
  int log_fd = -1; // -1: this process's stdout and stderr
  const std::vector<Fd> *inherited = nullptr;
  const std::vector<Command::Inherited> *inherit = nullptr;
  int report_fd = -1; // close-on-exec: closed by a successful exec, so the parent reads nothing
  int first_closed = STDERR_FILENO + 1;
  Group group = Group::Own;
  const Credentials *user = nullptr;
};

// What a child that cannot execute tells its parent: the step that failed and its errno. Less
// than PIPE_BUF: written whole.
struct ForkReport {
  int error = 0;
  char step[24] = {};
};

[[noreturn]] void fail_in_child(int report_fd, const char *step) {
  ForkReport report;
  report.error = errno;
  for (std::size_t i = 0; step[i] != '\0' && i + 1 < sizeof report.step; ++i) {
    report.step[i] = step[i];
  }
  [[maybe_unused]] const auto written = ::write(report_fd, &report, sizeof report);
  ::_exit(127);
}

// The user's groups, group and user, in that order (the group and groups can no longer be set
// once the user is not root), each checked. Raw system calls: glibc's wrappers would signal
// every thread of the process, which the child's copy of glibc may still believe it has.
const char *become_user(const Credentials &user) {
  if (::syscall(SYS_setgroups, user.groups.size(), user.groups.data()) != 0) {
    return "setgroups";
  }
  if (::syscall(SYS_setresgid, user.gid, user.gid, user.gid) != 0) {
    return "setresgid";
  }
  if (::syscall(SYS_setresuid, user.uid, user.uid, user.uid) != 0) {
    return "setresuid";
  }
  return nullptr;
}

// stdin, stdout and stderr, the inherited descriptors as their numbers, and no other descriptor
// but the report's, which its exec closes.
const char *hand_descriptors(const ForkPlan &plan) {
  if (::dup2(plan.null_fd, STDIN_FILENO) < 0) {
    return "/dev/null";
  }
  if (plan.log_fd >= 0 &&
      (::dup2(plan.log_fd, STDOUT_FILENO) < 0 || ::dup2(plan.log_fd, STDERR_FILENO) < 0)) {
    return "log file";
  }
  for (std::size_t i = 0; i < plan.inherit->size(); ++i) {
    if (::dup2((*plan.inherited)[i].get(), (*plan.inherit)[i].as) < 0) {
      return "dup2";
    }
  }
  for (int fd = STDERR_FILENO + 1; fd < plan.first_closed; ++fd) {
    if (!given_as(*plan.inherit, fd)) {
      ::close(fd); // one that is not open: nothing to do
    }
  }
  const auto report = static_cast<unsigned>(plan.report_fd);
  const auto first = static_cast<unsigned>(plan.first_closed);
  if (report > first && ::close_range(first, report - 1, 0) != 0) {
    return "close_range";
  }
  if (::close_range(report + 1, ~0U, 0) != 0) {
    return "close_range";
  }
  return nullptr;
}

[[noreturn]] void run_forked(const ForkPlan &plan) {
  // Every signal's default action first: a handler of this process must never run here.
  struct sigaction default_action {};
  default_action.sa_handler = SIG_DFL;
  for (int signal = 1; signal < NSIG; ++signal) {
    ::sigaction(signal, &default_action, nullptr); // SIGKILL, SIGSTOP and glibc's own refuse
  }
  if (plan.group == Group::Own && ::setpgid(0, 0) != 0) {
    fail_in_child(plan.report_fd, "setpgid");
  }
  if (plan.group == Group::Session && ::setsid() < 0) {
    fail_in_child(plan.report_fd, "setsid");
  }
  if (const char *failed = hand_descriptors(plan)) {
    fail_in_child(plan.report_fd, failed);
  }
  if (const char *failed = plan.user != nullptr ? become_user(*plan.user) : nullptr) {
    fail_in_child(plan.report_fd, failed);
  }
  // As the user: a folder it may not enter fails here, not in the program.
  if (plan.working_dir != nullptr && ::chdir(plan.working_dir) != 0) {
    fail_in_child(plan.report_fd, "chdir");
  }
  sigset_t none;
  ::sigemptyset(&none);
  ::sigprocmask(SIG_SETMASK, &none, nullptr);
  ::execve(plan.program, plan.argv, plan.envp);
  fail_in_child(plan.report_fd, "execve");
}

// One fork; the child's pid once it has executed the program, else its report (the child
// reaped).
std::variant<pid_t, ForkReport> fork_once(ForkPlan plan) {
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0) {
    return ForkReport{errno, "pipe"};
  }
  Fd read_end{ends[0]};
  Fd write_end = copy_above(ends[1], plan.first_closed);
  ::close(ends[1]);
  if (!write_end) {
    return ForkReport{errno, "fcntl"};
  }
  plan.report_fd = write_end.get();
  const pid_t pid = ::fork();
  if (pid == 0) {
    run_forked(plan);
  }
  if (pid < 0) {
    return ForkReport{errno, "fork"};
  }
  write_end.reset();
  ForkReport report;
  ssize_t size = 0;
  do {
    size = ::read(read_end.get(), &report, sizeof report);
  } while (size < 0 && errno == EINTR);
  if (size == 0) {
    return pid;
  }
  while (::waitpid(pid, nullptr, 0) < 0 && errno == EINTR) {
  }
  return size == static_cast<ssize_t>(sizeof report) ? report : ForkReport{EIO, "report"};
}

// start() for a command that changes user.
Expected<pid_t> start_forked(const Command &command, Group group, int log_fd) {
  const int above = first_free_number(command);
  auto inherited = copy_inherited(command);
  if (!inherited) {
    return tl::unexpected(std::move(inherited.error()));
  }
  const Fd opened_null{::open("/dev/null", O_RDONLY | O_CLOEXEC)};
  const Fd null = copy_above(opened_null.get(), above);
  const Fd log = log_fd >= 0 ? copy_above(log_fd, above) : Fd{};
  if (!null || (log_fd >= 0 && !log)) {
    return spawn_error(command, fmt::format("cannot prepare to execute {}: {}",
                                            command.program.string(), errno_text(errno)));
  }
  ExecStrings strings(command);
  const ForkPlan plan{.program = command.program.c_str(),
                      .argv = strings.argv.data(),
                      .envp = strings.envp.data(),
                      .working_dir =
                          command.working_dir.empty() ? nullptr : command.working_dir.c_str(),
                      .null_fd = null.get(),
                      .log_fd = log_fd >= 0 ? log.get() : -1,
                      .inherited = &*inherited,
                      .inherit = &command.inherit,
                      .report_fd = -1,
                      .first_closed = above,
                      .group = group,
                      .user = command.user ? &*command.user : nullptr};
  auto forked = fork_once(plan);
  // ETXTBSY: as in start().
  for (int delay_ms = 1; std::holds_alternative<ForkReport>(forked) &&
                         std::get<ForkReport>(forked).error == ETXTBSY && delay_ms <= 64;
       delay_ms *= 2) {
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    forked = fork_once(plan);
  }
  if (const auto *report = std::get_if<ForkReport>(&forked)) {
    const std::string step(report->step, ::strnlen(report->step, sizeof report->step));
    // The usual cause on a first try: a cache or run folder under one only its owner may enter
    // (a home folder, mktemp -d), which the user the process runs as cannot pass through.
    const bool unreachable = report->error == EACCES && (step == "chdir" || step == "execve");
    return spawn_error(
        command,
        fmt::format("cannot execute {} as user {}: {}: {}{}", command.program.string(),
                    command.user ? command.user->user : "", step, errno_text(report->error),
                    unreachable ? " (every folder above it must let that user pass: "
                                  "chmod o+x, or a node --cache-dir elsewhere, or the "
                                  "GPP's run_as in the node's DCD)"
                                : ""));
  }
  return std::get<pid_t>(forked);
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
  auto pid =
      command.user ? start_forked(command, group, log->get()) : start(command, group, log->get());
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
