// One way to start a process. Whatever rsca starts, a component process from the GPP, the
// daemons of `rsca domain up`, the programs of the integration tests, is started here, the same
// careful way:
// - the program is run as given, never looked up in PATH; argv[0] is its path;
// - whatever can be checked in this process is checked before anything starts (the program is an
//   executable regular file, the working directory exists, the variable names are names, the log
//   file opens), so a mistake is an error naming the program and no child is left behind; exec
//   failures come back from posix_spawn itself (glibc starts the child vfork-style and reports
//   the exec's errno);
// - the child gets stdin from /dev/null, stdout and stderr appended to the log file (or this
//   process's), the one descriptor the command hands over (its node link), and no other
//   descriptor of this process, close-on-exec or not;
// - an empty signal mask and every signal's default action: an ignored signal would stay ignored
//   across exec, and a blocked one blocked (a daemon started from a shell that ignores SIGINT
//   would never stop on it). Only glibc's own two signals below SIGRTMIN stay ignored when this
//   process handles them: no spawn attribute reaches them, and a glibc program handles them itself;
// - the process group or session the caller asks for;
// - the user the caller asks for (Command::user): its groups, group and user set in the child,
//   in that order and each checked, before it runs the program. posix_spawn cannot do that: such
//   a child is forked, and does only system calls until it executes the program.
// It returns the child's pid and a pidfd (readable once the child has exited): reaping is the
// caller's business, since the GPP reaps whole process groups and `rsca domain up` leaves its
// daemons running when it exits.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <sys/types.h>

#include "common/diagnostic.hpp"
#include "process/credentials.hpp"
#include "process/fd.hpp"

namespace rsca::process {

// Where the child stands among process groups and sessions.
enum class Group : std::uint8_t {
  Own,     // leads a process group of its own (its pid is the group's id): signalled as a whole
  Session, // leads a session of its own, so a terminal's Ctrl-C does not reach it (daemons)
  Caller,  // stays in the caller's process group, so it goes with it (test programs)
};

// What to run, with what, where, and where its output goes. Every member has a default, so a
// designated initializer names only what it sets.
struct Command {
  std::filesystem::path program{}; // run as is: no PATH search
  std::vector<std::string> args{}; // argv[1..]; argv[0] is the program's path
  // Added to the environment this process has; a name already there is overridden, and of a
  // name given twice the last value wins.
  std::vector<std::pair<std::string, std::string>> env{};
  std::filesystem::path working_dir{}; // empty: this process's working directory
  // stdout and stderr are appended to this file, its directories created if missing. Empty:
  // the child shares this process's stdout and stderr. stdin is always /dev/null.
  std::filesystem::path log_file{};
  // Descriptors of this process the child gets, each as descriptor `as` (above stderr): the node
  // link (protocol/node_link.hpp), the host's arena (shm/arena.hpp). Every other descriptor is
  // closed in the child.
  struct Inherited {
    int fd = -1;
    int as = 3;
  };
  std::vector<Inherited> inherit{};
  // Who the child runs as (this process must be root); none: this process's user.
  std::optional<Credentials> user{};
};

// A started process. Not reaped by its destructor: whoever started it reaps it, or leaves it to
// outlive this process.
struct Child {
  pid_t pid = 0;
  Fd pidfd; // close-on-exec; readable once the process has exited
};

// Starts the command's program in `group`; returns once the child runs it. Every failure is an
// error at the program (rule "execute"), e.g. "cannot execute /opt/x: no such file", and starts
// nothing.
Expected<Child> spawn(const Command &command, Group group);

// What spawn() does before anything starts, for another way to start the command (a fork
// server: process/fork_server.hpp): the checks, and the log file opened (an empty Fd when the
// command has none).
Expected<Fd> prepare_to_spawn(const Command &command);

// A pidfd for `pid` (close-on-exec), which need not be this process's child; empty on failure
// (errno says why).
Fd open_pidfd(pid_t pid);

// Waits until the process behind `pidfd` has exited; false when it still runs after `timeout`.
bool wait_exited(const Fd &pidfd, std::chrono::milliseconds timeout);

// An errno value as a message: "no such file", "permission denied", else strerror's text.
std::string errno_text(int error);

} // namespace rsca::process
