// The process launcher's private parts (gpp/process_launcher.hpp), shared by its files: what it
// knows about each launched process and its process group (a record), and what it does when a
// pidfd of a group fires or a group is to be stopped, in process_groups.cpp: reaping, finding
// the rest of a group in /proc, killing what a leader left behind, signalling a group. The
// launcher's state, its reaper thread and the escalation on terminate are in
// process_launcher.cpp. Nothing outside the GPP includes this header.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <sys/types.h>

#include "gpp/process_launcher.hpp"
#include "process/fd.hpp"

namespace rsca::gpp::detail {

using process::Fd;

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

// "SIGTERM", or "signal 40" for one without a name.
std::string signal_name(int signal);

// After a pidfd of the group fired: reaps, then decides whether the group is gone. The exits of
// leaders go to `exits`, for on_exit.
void settle(Record &record, std::vector<PendingExit> &exits);

// Sends `signal` to the record's process group (and to its leader should it have left it).
void signal_group(Record &record, int signal);

} // namespace rsca::gpp::detail
