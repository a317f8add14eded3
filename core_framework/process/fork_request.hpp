// The contract between a node and a fork server (process/fork_server.hpp): what one request to
// start a process carries, and the reply. Built and parsed here only, by both parties.
//
// A request is one SOCK_SEQPACKET message: "key\0value\0" pairs, in any order, with the
// descriptors the child gets as SCM_RIGHTS ancillary data, in the order of `fds` (the log file
// first when `log` is set). Keys: "program" (its argv[0]: the path it was asked for, which may
// name another link to the server's file), "arg" (one per argument, argv[1..] in order), "env"
// ("NAME=value", one per variable), "dir" (the working directory), "cpu" (one per CPU the child
// starts on), "fd" (the number the next inherited descriptor becomes), "log" ("1": the first
// descriptor is the log file, the child's stdout and stderr). A reply is "pid\0<pid>\0" or
// "error\0<text>\0". The fork server trusts its node (it is the node's child, over a socket pair
// only they hold), but a message is still checked: sizes are bounded, numbers parsed whole, keys
// known.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <sys/types.h>

#include <tl/expected.hpp>

namespace rsca::process {

// The environment variable that makes a component executable a fork server, and the descriptor
// it gets its socket as.
inline constexpr const char *kForkServerVariable = "RSCA_FORK_SERVER_FD";
inline constexpr int kForkServerFd = 3;
// The first message a fork server sends, once it serves: also what the node looks for in an
// executable's bytes before it starts one as a fork server (a program that does not serve would
// otherwise run with arguments it does not expect).
inline constexpr std::string_view kForkServerReady = "rsca fork server protocol 1: ready";
// Bounds on one message.
inline constexpr std::size_t kForkMessageMax = 64 * 1024;
inline constexpr std::size_t kForkFdsMax = 8;

struct ForkRequest {
  std::string program{};           // argv[0]; empty: the server's
  std::vector<std::string> args{}; // argv[1..]
  std::vector<std::pair<std::string, std::string>> env{};
  std::string working_dir{};     // empty: the fork server's
  std::vector<unsigned> cpus{};  // empty: the fork server's
  bool log = false;              // the first descriptor is the log file (stdout and stderr)
  std::vector<int> fd_numbers{}; // what each other descriptor becomes, in order
};

std::string encode(const ForkRequest &request);
// `fds` is how many descriptors came with the message: they must match what it says.
tl::expected<ForkRequest, std::string> decode_fork_request(std::string_view message,
                                                           std::size_t fds);

struct ForkReply {
  pid_t pid = 0;       // the started process, when error is empty
  std::string error{}; // why nothing started
};

std::string encode(const ForkReply &reply);
tl::expected<ForkReply, std::string> decode_fork_reply(std::string_view message);

} // namespace rsca::process
