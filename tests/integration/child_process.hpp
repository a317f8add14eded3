// Real processes for integration tests: started as rsca starts every process (process/spawn.hpp:
// stdin from /dev/null, default signal dispositions, no inherited descriptor) in the test's
// process group, with arguments and extra environment, always killed and reaped when the guard
// goes (even when the test fails), and waited for with a bound (a pidfd becomes readable when the
// process exits).
#pragma once

#include <chrono>
#include <csignal>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>

#include "process/spawn.hpp"

namespace rsca::test {

class ChildProcess {
public:
  using Environment = std::vector<std::pair<std::string, std::string>>;

  // Starts `path` with `args` (argv[1..]) and the test's environment with `overrides` set; its
  // stdout and stderr appended to `log_file`, or the test's own when it is empty.
  ChildProcess(const std::string &path, const std::vector<std::string> &args,
               const Environment &overrides, const std::filesystem::path &log_file = {}) {
    auto child =
        process::spawn({.program = path, .args = args, .env = overrides, .log_file = log_file},
                       process::Group::Caller);
    if (!child)
      FAIL("cannot start " << path << ": " << child.error().to_string());
    pid_ = child->pid;
    pidfd_ = std::move(child->pidfd);
  }

  ~ChildProcess() {
    if (pid_ > 0 && !status_) {
      ::kill(pid_, SIGKILL);
      int status = 0;
      ::waitpid(pid_, &status, 0); // SIGKILL cannot be ignored: this returns
    }
  }
  ChildProcess(const ChildProcess &) = delete;
  ChildProcess &operator=(const ChildProcess &) = delete;

  pid_t pid() const { return pid_; }
  void signal(int number) const { ::kill(pid_, number); }

  // The wait status once the process has exited, or nothing if it still runs after `timeout`.
  std::optional<int> wait_exit(std::chrono::milliseconds timeout) {
    if (status_)
      return status_;
    if (!process::wait_exited(pidfd_, timeout))
      return std::nullopt;
    int status = 0;
    if (::waitpid(pid_, &status, 0) == pid_)
      status_ = status;
    return status_;
  }

  // "exit 0", "exit 3", "signal 9": what the status means, for messages.
  static std::string describe(std::optional<int> status) {
    if (!status)
      return "still running";
    if (WIFEXITED(*status))
      return "exit " + std::to_string(WEXITSTATUS(*status));
    if (WIFSIGNALED(*status))
      return "signal " + std::to_string(WTERMSIG(*status));
    return "status " + std::to_string(*status);
  }

private:
  pid_t pid_ = -1;
  process::Fd pidfd_;
  std::optional<int> status_;
};

} // namespace rsca::test
