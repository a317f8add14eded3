// The GPP's (SCA ExecutableDevice) execute and terminate: starts component processes, each
// leading a process group of its own, reaps them as they exit and stops them with a bounded
// escalation SIGINT -> SIGTERM -> SIGKILL sent to the whole group.
//
// One reaper thread per launcher watches every child through a pidfd (Linux >= 5.3), so exits are
// noticed as they happen and nothing ever waits on a fixed sleep. The launcher makes its process
// a child subreaper (PR_SET_CHILD_SUBREAPER): processes a component leaves behind when its leader
// exits are re-parented to this process, and the reaper reaps them, so the process group is
// really gone when terminate() returns. A component's process group dies with its leader: when
// the leader exits on its own, whatever is left of its group is killed with SIGKILL.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <sys/types.h>

#include "common/diagnostic.hpp"
#include "process/spawn.hpp"

namespace rsca::gpp {

// The process id of a launched process; also the id of its process group.
using ProcessId = pid_t;

// What execute() starts (process/spawn.hpp says how: stdin from /dev/null, default signal
// dispositions, no inherited descriptor; here always in a process group of its own), and the
// name it goes by in logs.
struct ExecRequest : process::Command {
  std::string label; // names the process in logs; empty: the program's file name
};

struct ExitStatus {
  enum class Kind : std::uint8_t {
    Exited,    // exit() or a return from main: exit_code holds the code
    Signalled, // killed by a signal: signal holds its number
    Unknown,   // reaped by someone else in this process (a stray waitpid(-1)): nothing known
  };
  Kind kind = Kind::Unknown;
  int exit_code = 0;
  int signal = 0;
  bool core_dumped = false;
  // The process exited after terminate() was called for it. False means it exited on its own,
  // which for a component is a crash to report.
  bool requested = false;
  // The last signal terminate() had sent when the process exited (SIGINT, SIGTERM or SIGKILL):
  // how far the escalation went. 0 when terminate() was not called.
  int terminate_signal = 0;

  bool exited() const { return kind == Kind::Exited; }
  bool signalled() const { return kind == Kind::Signalled; }
};

// "exited with code 3", "killed by SIGSEGV (core dumped)", "exit status unknown".
std::string describe(const ExitStatus &status);

struct ProcessInfo {
  ProcessId pid = 0;
  std::string label;
  std::filesystem::path executable;
  std::chrono::system_clock::time_point started_at;
  std::filesystem::path log_file;
  bool running = false;           // the process itself has not exited yet
  std::optional<ExitStatus> exit; // set once it has exited and been reaped
};

struct TerminateOptions {
  std::chrono::milliseconds grace_sigint{1000};  // time to exit after SIGINT
  std::chrono::milliseconds grace_sigterm{1000}; // then after SIGTERM
  std::chrono::milliseconds grace_sigkill{2000}; // then after SIGKILL, before giving up
};

class ProcessLauncher {
public:
  // Called from the reaper thread when a launched process exits, after it has been reaped. It
  // must not block, and must not call terminate(), terminate_all() or wait_for_exit(). It may be
  // called while the launcher is being destroyed.
  using ExitCallback = std::function<void(ProcessId, ExitStatus)>;
  // How execute() starts a process, at the priority the node was started with: process::spawn
  // in a process group of its own, unless the launcher is given another way (a fork server,
  // gpp/fork_servers.hpp) that starts it as that would.
  using Starter = std::function<Expected<process::Child>(const ExecRequest &)>;

  explicit ProcessLauncher(ExitCallback on_exit = {}, Starter starter = {});
  // Terminates every process still running (escalation with the default options, all processes
  // at once), then stops the reaper.
  ~ProcessLauncher();
  ProcessLauncher(const ProcessLauncher &) = delete;
  ProcessLauncher &operator=(const ProcessLauncher &) = delete;

  // Starts the process; returns once it runs the executable. A missing or non-executable file,
  // a bad working directory or log file is an error and starts nothing.
  Expected<ProcessId> execute(const ExecRequest &request);

  // Stops the process group of `pid`: SIGINT, then SIGTERM, then SIGKILL, each followed by a
  // wait for the group to be gone of at most its grace time. Returns when the process and every
  // other member of its group have exited and been reaped, and on_exit has been called; an error
  // for an unknown pid or a group still alive after SIGKILL. A process that has already exited
  // is not an error.
  Expected<void> terminate(ProcessId pid, TerminateOptions options = {});
  // terminate() for every process not yet gone, all at once.
  Expected<void> terminate_all(TerminateOptions options = {});

  // Launched processes, running or exited (the latest exited ones are remembered), oldest first.
  std::vector<ProcessInfo> list() const;
  bool running(ProcessId pid) const;
  // The exit status once the process has exited and on_exit has been called for it; nullopt on
  // timeout or for an unknown pid.
  std::optional<ExitStatus> wait_for_exit(ProcessId pid, std::chrono::milliseconds timeout);

private:
  struct State;
  std::unique_ptr<State> state_;
};

} // namespace rsca::gpp
