// The GPP's process launcher on real processes: exits reported with their status, output in the
// log file, arguments and environment passed, errors before anything starts, the SIGINT ->
// SIGTERM -> SIGKILL escalation on whole process groups, and no zombie left behind. Nothing here
// sleeps to wait: tests wait on conditions (on_exit, a FIFO the child writes, a pidfd) with
// timeouts.
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <string>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>

#include "gpp/host_info.hpp"
#include "gpp/process_launcher.hpp"
#include "process/spawn.hpp"
#include "temp_dir.hpp"
#include "test_files.hpp"

using namespace std::chrono_literals;
using rsca::gpp::ExecRequest;
using rsca::gpp::ProcessId;
using rsca::gpp::ProcessLauncher;
using rsca::gpp::TerminateOptions;
using rsca::test::slurp;
using rsca::test::TempDir;
namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

// Collects what on_exit reports, for the test thread to wait on.
class ExitLog {
public:
  ProcessLauncher::ExitCallback callback() {
    return [this](ProcessId pid, rsca::gpp::ExitStatus status) {
      {
        const std::lock_guard lock(mutex_);
        exits_[pid] = status;
        ++calls_;
      }
      changed_.notify_all();
    };
  }

  std::optional<rsca::gpp::ExitStatus> wait(ProcessId pid, std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    changed_.wait_for(lock, timeout, [&] { return exits_.count(pid) != 0; });
    const auto it = exits_.find(pid);
    return it != exits_.end() ? std::optional{it->second} : std::nullopt;
  }

  int calls() const {
    const std::lock_guard lock(mutex_);
    return calls_;
  }

private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::map<ProcessId, rsca::gpp::ExitStatus> exits_;
  int calls_ = 0;
};

// A named pipe a child writes a line to ("ready", its child's pid); the test waits for the line.
class Fifo {
public:
  explicit Fifo(fs::path path) : path_(std::move(path)) {
    REQUIRE(::mkfifo(path_.c_str(), 0600) == 0);
    fd_ = ::open(path_.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    REQUIRE(fd_ >= 0);
  }
  ~Fifo() { ::close(fd_); }
  Fifo(const Fifo &) = delete;
  Fifo &operator=(const Fifo &) = delete;
  const fs::path &path() const { return path_; }

  std::optional<std::string> read_line(std::chrono::milliseconds timeout) {
    const auto deadline = Clock::now() + timeout;
    for (;;) {
      if (const auto newline = buffer_.find('\n'); newline != std::string::npos) {
        auto line = buffer_.substr(0, newline);
        buffer_.erase(0, newline + 1);
        return line;
      }
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
      pollfd pfd{fd_, POLLIN, 0};
      if (left <= 0ms || ::poll(&pfd, 1, static_cast<int>(left.count())) <= 0) {
        return std::nullopt;
      }
      char chunk[256];
      const auto n = ::read(fd_, chunk, sizeof chunk);
      if (n == 0) {
        return std::nullopt; // the writer closed without a full line
      }
      if (n > 0) {
        buffer_.append(chunk, static_cast<std::size_t>(n));
      }
    }
  }

private:
  fs::path path_;
  int fd_ = -1;
  std::string buffer_;
};

// Exists in /proc: running, or a zombie nobody has reaped.
bool process_exists(pid_t pid) {
  return fs::exists(fs::path("/proc") / std::to_string(pid));
}

bool group_exists(pid_t group) {
  return ::kill(-group, 0) == 0 || errno != ESRCH;
}

std::optional<char> process_state(pid_t pid) {
  const auto text = rsca::gpp::read_proc_file(fs::path("/proc") / std::to_string(pid) / "stat");
  const auto paren = text ? text->rfind(')') : std::string::npos;
  if (paren == std::string::npos || paren + 2 >= text->size()) {
    return std::nullopt;
  }
  return (*text)[paren + 2];
}

// This process's children, from every thread's /proc children list.
std::set<pid_t> children() {
  std::set<pid_t> pids;
  for (const auto &task : fs::directory_iterator("/proc/self/task")) {
    std::istringstream list(rsca::gpp::read_proc_file(task.path() / "children").value_or(""));
    for (pid_t pid = 0; list >> pid;) {
      pids.insert(pid);
    }
  }
  return pids;
}

std::vector<pid_t> zombie_children() {
  std::vector<pid_t> zombies;
  for (const auto pid : children()) {
    if (process_state(pid) == 'Z') {
      zombies.push_back(pid);
    }
  }
  return zombies;
}

ExecRequest shell(std::string script, std::vector<std::string> parameters = {}) {
  ExecRequest request;
  request.program = "/bin/sh";
  request.args = {"-c", std::move(script), "sh"};
  request.args.insert(request.args.end(), parameters.begin(), parameters.end());
  return request;
}

ProcessId launch(ProcessLauncher &launcher, const ExecRequest &request) {
  auto pid = launcher.execute(request);
  INFO((pid ? std::string{} : pid.error().to_string()));
  REQUIRE(pid.has_value());
  return *pid;
}

void check_gone(pid_t pid) {
  INFO("pid " << pid);
  CHECK_FALSE(process_exists(pid));
  CHECK_FALSE(group_exists(pid));
}

} // namespace

TEST_CASE("a process that exits on its own is reported through on_exit", "[process]") {
  ExitLog exits;
  ProcessLauncher launcher(exits.callback());
  ExecRequest request;
  request.program = "/bin/true";
  const auto pid = launch(launcher, request);

  const auto status = exits.wait(pid, 10s);
  REQUIRE(status.has_value());
  CHECK(status->exited());
  CHECK(status->exit_code == 0);
  CHECK_FALSE(status->requested);
  CHECK(status->terminate_signal == 0);
  CHECK_FALSE(launcher.running(pid));
  CHECK_FALSE(process_exists(pid)); // reaped before on_exit is called
  const auto waited = launcher.wait_for_exit(pid, 10s);
  REQUIRE(waited.has_value());
  CHECK(waited->exited());
  CHECK(rsca::gpp::describe(*waited) == "exited with code 0");
}

TEST_CASE("the exit code comes through", "[process]") {
  ExitLog exits;
  ProcessLauncher launcher(exits.callback());
  const auto pid = launch(launcher, shell("exit 3"));
  const auto status = launcher.wait_for_exit(pid, 10s);
  REQUIRE(status.has_value());
  CHECK(status->exited());
  CHECK(status->exit_code == 3);
  CHECK_FALSE(status->requested);
  CHECK(exits.wait(pid, 0ms)->exit_code == 3); // on_exit has run when wait_for_exit returns
}

TEST_CASE("stdout and stderr are appended to the log file, its directories created", "[process]") {
  TempDir dir;
  const auto log = dir.path() / "logs" / "nested" / "component.log";
  ProcessLauncher launcher;
  for (const std::string run : {"first", "second"}) {
    auto request = shell("echo \"$1 to stdout\"; echo \"$1 to stderr\" >&2", {run});
    request.log_file = log;
    const auto pid = launch(launcher, request);
    REQUIRE(launcher.wait_for_exit(pid, 10s).has_value());
  }
  const auto text = slurp(log);
  CHECK(text == "first to stdout\nfirst to stderr\nsecond to stdout\nsecond to stderr\n");
}

TEST_CASE("arguments, environment and working directory reach the process", "[process]") {
  TempDir dir;
  auto request = shell("echo \"$FOO $1\"; echo \"$PATH\"; pwd", {"bar baz"});
  request.env = {{"FOO", "first"}, {"FOO", "hello"}}; // the last value of a name wins
  request.working_dir = dir.path();
  request.log_file = dir.path() / "out.log";
  ProcessLauncher launcher;
  const auto pid = launch(launcher, request);
  const auto status = launcher.wait_for_exit(pid, 10s);
  REQUIRE(status.has_value());
  CHECK(status->exit_code == 0);
  const char *path = std::getenv("PATH");
  const auto expected = "hello bar baz\n" + std::string(path != nullptr ? path : "") + "\n" +
                        dir.path().string() + "\n";
  CHECK(slurp(request.log_file) == expected);
}

TEST_CASE("the process gets /dev/null as stdin and none of the launcher's descriptors",
          "[process]") {
  TempDir dir;
  // Not close-on-exec: it would leak into a child made with a plain fork and exec.
  const int leaky = ::open("/dev/null", O_RDONLY);
  REQUIRE(leaky >= 3);
  auto request = shell("readlink /proc/$$/fd/0; cd /proc/$$/fd && echo *");
  request.log_file = dir.path() / "fds.log";
  ProcessLauncher launcher;
  const auto pid = launch(launcher, request);
  REQUIRE(launcher.wait_for_exit(pid, 10s).has_value());
  ::close(leaky);
  // 3 is the directory the shell has open while it expands the *.
  CHECK(slurp(request.log_file) == "/dev/null\n0 1 2 3\n");
}

TEST_CASE("what cannot be executed is an error and starts nothing", "[process]") {
  TempDir dir;
  ProcessLauncher launcher;
  const auto before = children();
  const auto error_of = [&](const ExecRequest &request) {
    const auto pid = launcher.execute(request);
    REQUIRE_FALSE(pid.has_value());
    REQUIRE(pid.error().diagnostics().size() == 1);
    return pid.error().diagnostics().front().message;
  };

  ExecRequest missing;
  missing.program = "/nonexistent/rsca/component";
  CHECK(error_of(missing) == "cannot execute /nonexistent/rsca/component: no such file");

  const auto script = dir.path() / "not_executable.sh";
  std::ofstream(script) << "#!/bin/sh\nexit 0\n";
  fs::permissions(script, fs::perms::owner_read | fs::perms::owner_write);
  ExecRequest not_executable;
  not_executable.program = script;
  CHECK(error_of(not_executable) == "cannot execute " + script.string() + ": permission denied");

  ExecRequest directory;
  directory.program = dir.path();
  CHECK(error_of(directory) == "cannot execute " + dir.path().string() + ": is a directory");

  auto bad_directory = shell("exit 0");
  bad_directory.working_dir = dir.path() / "missing";
  CHECK(error_of(bad_directory) == "cannot use working directory " +
                                       bad_directory.working_dir.string() + ": no such directory");

  auto bad_variable = shell("exit 0");
  bad_variable.env = {{"A=B", "c"}};
  CHECK(error_of(bad_variable) == "invalid environment variable name \"A=B\"");

  CHECK(launcher.list().empty());
  CHECK(children() == before);
}

TEST_CASE("terminate escalates to SIGTERM when SIGINT is ignored", "[process]") {
  TempDir dir;
  Fifo fifo(dir.path() / "ready");
  ExitLog exits;
  ProcessLauncher launcher(exits.callback());
  const auto pid = launch(launcher, shell("trap '' INT; echo ready > \"$1\"; "
                                          "while :; do sleep 0.05; done",
                                          {fifo.path()}));
  REQUIRE(fifo.read_line(10s) == "ready");

  const auto start = Clock::now();
  const auto stopped = launcher.terminate(pid, {.grace_sigint = 300ms, .grace_sigterm = 10s});
  const auto elapsed = Clock::now() - start;
  INFO((stopped ? std::string{} : stopped.error().to_string()));
  REQUIRE(stopped.has_value());
  CHECK(elapsed >= 300ms); // SIGINT was given its grace
  CHECK(elapsed < 5s);     // SIGTERM did it, long before its grace ran out

  const auto status = launcher.wait_for_exit(pid, 0ms); // terminate returned: already reported
  REQUIRE(status.has_value());
  CHECK(status->signalled());
  CHECK(status->signal == SIGTERM);
  CHECK(status->requested);
  CHECK(status->terminate_signal == SIGTERM);
  CHECK(exits.wait(pid, 0ms)->signal == SIGTERM);
  CHECK_FALSE(launcher.running(pid));
  check_gone(pid);
}

TEST_CASE("terminate kills a process that ignores SIGINT and SIGTERM", "[process]") {
  TempDir dir;
  Fifo fifo(dir.path() / "ready");
  ProcessLauncher launcher;
  const auto pid = launch(launcher, shell("trap '' INT TERM; echo ready > \"$1\"; "
                                          "while :; do sleep 0.05; done",
                                          {fifo.path()}));
  REQUIRE(fifo.read_line(10s) == "ready");

  const auto start = Clock::now();
  const TerminateOptions options{
      .grace_sigint = 200ms, .grace_sigterm = 200ms, .grace_sigkill = 2s};
  REQUIRE(launcher.terminate(pid, options).has_value());
  const auto elapsed = Clock::now() - start;
  CHECK(elapsed >= 400ms);
  CHECK(elapsed < 2400ms + 1s); // the bounds, and some slack for a loaded machine

  const auto status = launcher.wait_for_exit(pid, 0ms);
  REQUIRE(status.has_value());
  CHECK(status->signalled());
  CHECK(status->signal == SIGKILL);
  CHECK(status->requested);
  CHECK(status->terminate_signal == SIGKILL);
  check_gone(pid);
}

TEST_CASE("terminate stops the whole process group, grandchildren included", "[process]") {
  TempDir dir;
  Fifo fifo(dir.path() / "grandchild");
  ProcessLauncher launcher;
  // A background job of a non-interactive shell ignores SIGINT: the grandchild outlives the
  // shell, which SIGINT kills, and has to be stopped by SIGTERM.
  const auto pid = launch(launcher, shell("sleep 1000 & echo $! > \"$1\"; wait", {fifo.path()}));
  const auto line = fifo.read_line(10s);
  REQUIRE(line.has_value());
  const pid_t grandchild = std::stoi(*line);
  REQUIRE(process_exists(grandchild));
  CHECK(::getpgid(grandchild) == pid);

  const auto stopped = launcher.terminate(pid, {.grace_sigint = 300ms, .grace_sigterm = 10s});
  INFO((stopped ? std::string{} : stopped.error().to_string()));
  REQUIRE(stopped.has_value());
  const auto status = launcher.wait_for_exit(pid, 0ms);
  REQUIRE(status.has_value());
  CHECK(status->signal == SIGINT);
  CHECK(status->requested);
  CHECK_FALSE(process_exists(grandchild));
  check_gone(pid);
  CHECK(zombie_children().empty());
}

TEST_CASE("what a process leaves in its group when it exits on its own is killed", "[process]") {
  TempDir dir;
  Fifo fifo(dir.path() / "grandchild");
  ExitLog exits;
  ProcessLauncher launcher(exits.callback());
  // The grandchild ignores every signal terminate() would send before SIGKILL.
  const auto pid = launch(launcher, shell("trap '' INT TERM HUP; sleep 1000 & echo $! > \"$1\"; "
                                          "exit 3",
                                          {fifo.path()}));
  const auto line = fifo.read_line(10s);
  REQUIRE(line.has_value());
  const pid_t grandchild = std::stoi(*line);
  const auto pidfd = rsca::process::open_pidfd(grandchild);
  // Killed by the launcher (nothing else here would kill it), or already killed and reaped.
  if (pidfd) {
    CHECK(rsca::process::wait_exited(pidfd, 10s));
  } else {
    CHECK(errno == ESRCH);
  }

  const auto status = exits.wait(pid, 10s);
  REQUIRE(status.has_value());
  CHECK(status->exit_code == 3);
  CHECK_FALSE(status->requested);
  // Returns once the group is gone; nothing is left to signal.
  REQUIRE(launcher.terminate(pid).has_value());
  CHECK_FALSE(process_exists(grandchild));
  check_gone(pid);
  CHECK(zombie_children().empty());
}

TEST_CASE("a crashing process is reported with its signal", "[process]") {
  TempDir dir;
  ExitLog exits;
  ProcessLauncher launcher(exits.callback());
  auto request = shell("ulimit -c 0; kill -SEGV $$");
  request.working_dir = dir.path();
  const auto pid = launch(launcher, request);
  const auto status = exits.wait(pid, 10s);
  REQUIRE(status.has_value());
  CHECK(status->signalled());
  CHECK(status->signal == SIGSEGV);
  CHECK_FALSE(status->requested);
  CHECK(status->terminate_signal == 0);
  CHECK(rsca::gpp::describe(*status) == "killed by SIGSEGV");
  CHECK_FALSE(process_exists(pid));
}

TEST_CASE("the destructor stops every running process", "[process]") {
  TempDir dir;
  Fifo fifo(dir.path() / "ready");
  ExitLog exits;
  std::vector<ProcessId> pids;
  {
    ProcessLauncher launcher(exits.callback());
    for (int i = 0; i < 3; ++i) {
      ExecRequest request;
      request.program = "/bin/sleep";
      request.args = {"1000"};
      pids.push_back(launch(launcher, request));
    }
    pids.push_back(launch(launcher, shell("trap '' INT; echo ready > \"$1\"; "
                                          "while :; do sleep 0.05; done",
                                          {fifo.path()})));
    REQUIRE(fifo.read_line(10s) == "ready");
    CHECK(launcher.list().size() == 4);
  }
  CHECK(exits.calls() == 4);
  for (const auto pid : pids) {
    const auto status = exits.wait(pid, 0ms);
    REQUIRE(status.has_value());
    CHECK(status->requested);
    CHECK(status->signalled());
    check_gone(pid);
  }
  CHECK(exits.wait(pids.back(), 0ms)->signal == SIGTERM);
}

TEST_CASE("many short processes leave no zombies", "[process]") {
  ExitLog exits;
  ProcessLauncher launcher(exits.callback());
  std::vector<ProcessId> pids;
  for (int i = 0; i < 50; ++i) {
    pids.push_back(launch(launcher, shell("exit $1", {std::to_string(i % 7)})));
  }
  for (std::size_t i = 0; i < pids.size(); ++i) {
    const auto status = exits.wait(pids[i], 10s);
    REQUIRE(status.has_value());
    CHECK(status->exit_code == static_cast<int>(i % 7));
  }
  CHECK(exits.calls() == 50);
  const auto list = launcher.list();
  CHECK(list.size() == 50);
  CHECK(std::none_of(list.begin(), list.end(), [](const auto &info) { return info.running; }));
  CHECK(zombie_children().empty());
  const auto remaining = children();
  for (const auto pid : pids) {
    CHECK(remaining.count(pid) == 0);
  }
  errno = 0;
  CHECK(::waitpid(-1, nullptr, WNOHANG) <= 0); // nothing left to reap
}

TEST_CASE("list, running and wait_for_exit describe the launched processes", "[process]") {
  TempDir dir;
  ProcessLauncher launcher;
  ExecRequest request;
  request.program = "/bin/sleep";
  request.args = {"1000"};
  request.label = "sleeper";
  request.log_file = dir.path() / "sleeper.log";
  const auto before = std::chrono::system_clock::now();
  const auto pid = launch(launcher, request);
  const auto after = std::chrono::system_clock::now();

  CHECK(launcher.running(pid));
  CHECK_FALSE(launcher.wait_for_exit(pid, 20ms).has_value()); // still running: times out
  auto list = launcher.list();
  REQUIRE(list.size() == 1);
  CHECK(list[0].pid == pid);
  CHECK(list[0].label == "sleeper");
  CHECK(list[0].executable == "/bin/sleep");
  CHECK(list[0].log_file == request.log_file);
  CHECK(list[0].running);
  CHECK_FALSE(list[0].exit.has_value());
  CHECK(list[0].started_at >= before);
  CHECK(list[0].started_at <= after);

  REQUIRE(launcher.terminate(pid).has_value());
  CHECK_FALSE(launcher.running(pid));
  list = launcher.list();
  REQUIRE(list.size() == 1);
  CHECK_FALSE(list[0].running);
  REQUIRE(list[0].exit.has_value());
  CHECK(list[0].exit->signal == SIGINT);
  CHECK(list[0].exit->requested);

  CHECK(launcher.terminate(pid).has_value()); // already gone: nothing to do
  const auto unknown = launcher.terminate(pid + 100000);
  REQUIRE_FALSE(unknown.has_value());
  CHECK_THAT(unknown.error().to_string(), Catch::Contains("no process"));
  CHECK_FALSE(launcher.running(pid + 100000));
  CHECK_FALSE(launcher.wait_for_exit(pid + 100000, 0ms).has_value());
}
