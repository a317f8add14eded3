// node.logs: pieces of the logs of the processes a node's GPP started (their stdout and stderr,
// <log folder>/APPLICATION/COMPONENT.log), for `rsca logs` on any host. The caller names an
// application and a component, never a path: both are checked as names, and the path is made
// here, inside the node's log folder.
//
// Logs are rotated by size (node option --log-max-kib), keeping one older file, LOG.1: the node
// copies the log there and empties it (copytruncate), because the process writes to its own
// descriptor of the file (appending: its next write lands at the emptied file's start), which a
// rename would leave writing into LOG.1. What the process writes between the copy and the
// truncation is lost; a rotation takes a few milliseconds, once per --log-max-kib logged.
#pragma once

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/diagnostic.hpp"
#include "control/caller.hpp"
#include "protocol/node_ops.hpp"

namespace rsca::node {

// The piece of the log `request` asks for. `running`: the processes the node runs (a hosted
// component's log is its component host's, found by the request's pid). Reads go across a
// rotation: a tail shorter than asked begins in LOG.1, and an offset past the log's end (it was
// rotated since) reads the rest of LOG.1 from there, then the log from its start.
control::CallResult<protocol::node::LogsReply>
read_log(const std::filesystem::path &log_dir, const protocol::node::LogsRequest &request,
         const std::vector<protocol::node::ProcessRecord> &running);

// A log and the older file its rotation keeps: LOG.1 for a process's (previous_of), the name
// spdlog's rotating sink gives for the node daemon's own (node/daemon_log.hpp).
struct LogFiles {
  std::filesystem::path log;
  std::filesystem::path previous;
};

std::filesystem::path previous_of(const std::filesystem::path &log);

// The piece of `files` from `offset` (absent: their tail) of at most `max_bytes` (clamped to
// LogsRequest's bounds), whole lines only, read across a rotation as read_log says. `what` names
// the log in errors; the reply names it relative to `log_dir`.
control::CallResult<protocol::node::LogsReply> read_piece(const LogFiles &files,
                                                          const std::filesystem::path &log_dir,
                                                          std::optional<std::uint64_t> offset,
                                                          std::optional<std::uint64_t> max_bytes,
                                                          const std::string &what);

// Deletes the logs (LOG and LOG.1) in the application folders of `log_dir` that no process of
// `running` writes and that nothing wrote to for `keep`, then the application folders left
// empty: the logs of released applications and of rolled-back launches (rsca logs --failed)
// are kept that long, not for ever. The node daemon's own log, a file of `log_dir` itself, is
// not touched. How many files it deleted.
std::size_t sweep_logs(const std::filesystem::path &log_dir,
                       const std::vector<protocol::node::ProcessRecord> &running,
                       std::chrono::seconds keep);

// Copies `log` to `log`.1 and empties it when it holds more than `max_bytes`; whether it did.
Expected<bool> rotate_if_over(const std::filesystem::path &log, std::uint64_t max_bytes);

// The end of `log` for a report of its process's exit: its last whole lines (and a last one
// unended: a dying process may not end it) after `from` (where the process began writing it;
// ignored when the log is shorter, rotated since), at most `max_lines` of them and `max_bytes`
// bytes of valid UTF-8; empty when there is no log.
std::string log_tail(const std::filesystem::path &log, std::uint64_t from, std::size_t max_lines,
                     std::size_t max_bytes);

// `bytes` as valid UTF-8 (JSON text must be): each byte that is not part of a valid sequence
// becomes U+FFFD.
std::string utf8_or_replaced(std::string_view bytes);

} // namespace rsca::node
