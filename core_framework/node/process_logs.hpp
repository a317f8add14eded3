// node.logs: pieces of the logs of the processes a node's GPP started (their stdout and stderr,
// <log folder>/APPLICATION/COMPONENT.log), for `rsca logs` on any host. The caller names an
// application and a component, never a path: both are checked as names, and the path is made
// here, inside the node's log folder.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "control/caller.hpp"
#include "protocol/node_ops.hpp"

namespace rsca::node {

// The piece of the log `request` asks for. `running`: the processes the node runs (a hosted
// component's log is its component host's, found by the request's pid). A log read from an
// offset past its end (it was rotated or truncated since) is read from its start.
control::CallResult<protocol::node::LogsReply>
read_log(const std::filesystem::path &log_dir, const protocol::node::LogsRequest &request,
         const std::vector<protocol::node::ProcessRecord> &running);

// `bytes` as valid UTF-8 (JSON text must be): each byte that is not part of a valid sequence
// becomes U+FFFD.
std::string utf8_or_replaced(std::string_view bytes);

} // namespace rsca::node
