// The node daemon's own log as a file beside its processes' logs, <log folder>/rsca-noded.NODE.log,
// so that `rsca logs NODE` reads it from any host (node.daemon_logs). The daemon goes on logging
// to its standard error (the journal under systemd) as well.
//
// It is rotated by size by the daemon's own spdlog sink, which renames it (the daemon owns the
// file, so nothing else writes to it): one older file is kept, named as spdlog names it
// (rsca-noded.NODE.1.log). Its lines start as a component's do ("[YYYY-MM-DD HH:MM:SS.mmm]",
// local time), so `rsca logs --since` reads both alike.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string_view>

#include "common/diagnostic.hpp"
#include "control/caller.hpp"
#include "protocol/node_ops.hpp"

namespace rsca::node {

// The log of node `node` in `log_dir`. A node's name needs no folder: it is a file of the log
// folder, whose folders are applications'.
std::filesystem::path daemon_log_file(const std::filesystem::path &log_dir, std::string_view node);

// The default logger writes to `file` too, rotated past `max_bytes` (0: never), each message
// flushed (a reader sees it at once). The sinks it had stay, as do their format and the level.
// Call in main before any other thread logs: the default logger is replaced.
Expected<void> log_also_to_file(const std::filesystem::path &file, std::uint64_t max_bytes);

// The piece of the daemon's log `request` asks for, across a rotation as read_log reads.
control::CallResult<protocol::node::LogsReply>
read_daemon_log(const std::filesystem::path &log_dir, std::string_view node,
                const protocol::node::DaemonLogsRequest &request);

} // namespace rsca::node
