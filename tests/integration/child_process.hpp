// Real processes for integration tests: spawned with arguments and extra environment, always
// killed and reaped when the guard goes (even when the test fails), and waited for with a bound
// (a pidfd becomes readable when the process exits).
#pragma once

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <poll.h>
#include <spawn.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>

extern char **environ;

namespace rsca::test {

class ChildProcess {
public:
  using Environment = std::vector<std::pair<std::string, std::string>>;

  // Starts `path` with `args` (argv[1..]) and the test's environment with `overrides` set.
  ChildProcess(const std::string &path, const std::vector<std::string> &args,
               const Environment &overrides) {
    std::vector<std::string> argv_text{path};
    argv_text.insert(argv_text.end(), args.begin(), args.end());
    std::vector<std::string> env_text = environment_with(overrides);
    std::vector<char *> argv = pointers(argv_text);
    std::vector<char *> envp = pointers(env_text);
    // Default signal dispositions and an empty mask, whatever the test process has.
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    sigset_t none, defaults;
    sigemptyset(&none);
    sigemptyset(&defaults);
    sigaddset(&defaults, SIGINT);
    sigaddset(&defaults, SIGTERM);
    posix_spawnattr_setsigmask(&attributes, &none);
    posix_spawnattr_setsigdefault(&attributes, &defaults);
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
    const int rc = posix_spawn(&pid_, path.c_str(), nullptr, &attributes, argv.data(), envp.data());
    posix_spawnattr_destroy(&attributes);
    if (rc != 0) {
      pid_ = -1;
      FAIL("cannot start " << path << ": " << std::strerror(rc));
    }
    // glibc's <sys/pidfd.h> lacks extern "C" in this version: the system call directly.
    pidfd_ = static_cast<int>(::syscall(SYS_pidfd_open, pid_, 0));
    if (pidfd_ < 0) {
      const int error = errno;
      ::kill(pid_, SIGKILL); // the destructor does not run for a constructor that throws
      int status = 0;
      ::waitpid(pid_, &status, 0);
      FAIL("pidfd_open failed: " << std::strerror(error));
    }
  }

  ~ChildProcess() {
    if (pid_ > 0 && !status_) {
      ::kill(pid_, SIGKILL);
      int status = 0;
      ::waitpid(pid_, &status, 0); // SIGKILL cannot be ignored: this returns
    }
    if (pidfd_ >= 0)
      ::close(pidfd_);
  }
  ChildProcess(const ChildProcess &) = delete;
  ChildProcess &operator=(const ChildProcess &) = delete;

  pid_t pid() const { return pid_; }
  void signal(int number) const { ::kill(pid_, number); }

  // The wait status once the process has exited, or nothing if it still runs after `timeout`.
  std::optional<int> wait_exit(std::chrono::milliseconds timeout) {
    if (status_)
      return status_;
    pollfd fd{pidfd_, POLLIN, 0};
    if (::poll(&fd, 1, static_cast<int>(timeout.count())) <= 0)
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
  static std::vector<std::string> environment_with(const Environment &overrides) {
    std::map<std::string, std::string> variables;
    for (char **e = environ; *e != nullptr; ++e) {
      const std::string entry = *e;
      const auto equals = entry.find('=');
      if (equals != std::string::npos)
        variables[entry.substr(0, equals)] = entry.substr(equals + 1);
    }
    for (const auto &[name, value] : overrides)
      variables[name] = value;
    std::vector<std::string> out;
    for (const auto &[name, value] : variables)
      out.push_back(name + "=" + value);
    return out;
  }

  static std::vector<char *> pointers(std::vector<std::string> &texts) {
    std::vector<char *> out;
    for (auto &t : texts)
      out.push_back(t.data());
    out.push_back(nullptr);
    return out;
  }

  pid_t pid_ = -1;
  int pidfd_ = -1;
  std::optional<int> status_;
};

} // namespace rsca::test
