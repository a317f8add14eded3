// The node link's framing (protocol/node_link.hpp) over a Unix stream socket: whole frames out,
// whole frames in. Both parties use it: the process's NodeLink (control/node_link.hpp) and the
// node's ProcessLinks (node/process_links.hpp).
#pragma once

#include <chrono>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include <sys/types.h>

#include <tl/expected.hpp>

#include "process/fd.hpp"
#include "protocol/node_link.hpp"
#include "protocol/status.hpp"

namespace rsca::control {

// A Reply as the result of the call it answers, and a call's result as its Reply.
protocol::CallResult<nlohmann::json> reply_result(const protocol::link::Reply &reply);
protocol::link::Reply link_reply(const std::string &id,
                                 const protocol::CallResult<nlohmann::json> &result);

// Makes a connected pair of Unix stream sockets, close-on-exec: [0] for the node, [1] for the
// process it starts (the spawn hands it over as kNodeLinkFd).
tl::expected<std::pair<process::Fd, process::Fd>, std::string> make_link_pair();

// The node's control socket: a Unix stream socket at `path` that local clients (the CLI) connect
// to for a link of their own, instead of joining DDS (node/process_links.hpp). A stale socket file
// (nobody accepts on it) is replaced, a live one is refused; the file is made mode 0660, so the
// node's user and group may connect.
tl::expected<process::Fd, std::string> listen_for_links(const std::string &path);
// A client's link to the node listening at `path`, close-on-exec.
tl::expected<process::Fd, std::string> connect_link(const std::string &path);

namespace detail {
// A Unix socket bound at `path` (not yet listening) whose file is never more open than `mode`
// less the umask, not even for an instant: listen_for_links then sets `mode` exactly.
tl::expected<process::Fd, std::string> bind_unix_socket(const std::string &path, mode_t mode);
} // namespace detail

// A frame's bytes on a link: its text's length, 4 bytes big-endian, then the text.
std::string wire_of(std::string_view text);

// Writes frames to a link, whole, from any thread. The socket is blocking with a send timeout:
// a peer that stops reading fails a write after `timeout`, never holds its writer forever; a
// frame cut by that ends the link (shutdown), since the stream can no longer be read.
class LinkWriter {
public:
  explicit LinkWriter(int fd, std::chrono::milliseconds timeout = std::chrono::seconds(5));
  tl::expected<void, std::string> send(const protocol::link::Frame &frame);

private:
  int fd_;
  std::mutex mutex_;
};

// Collects the bytes read from a link and cuts them into frames.
//
// A frame whose body nests deeper than protocol::kMaxJsonDepth is refused without ending the link
// (its body is never built): a request is answered bad request (answers()), a reply becomes a
// failed one for the call it answers, an announcement is dropped.
class FrameReader {
public:
  // Reads what the socket has (once, without waiting: call it when poll says it is readable) and
  // appends the whole frames it completes to `frames`. False, with why, at the end of the link (the
  // peer closed it or died) or on a frame that breaks the protocol; the link is then to be closed.
  bool read_from(int fd, std::vector<protocol::link::Frame> &frames, std::string &why);
  // The replies owed to the requests refused since the last call, for the caller to send.
  std::vector<protocol::link::Reply> answers();

private:
  bool cut(std::vector<protocol::link::Frame> &frames, std::string &why);
  // A frame parse_json refused for its nesting: what is made of it, or false if it breaks the
  // protocol all the same.
  bool refuse_deep(std::string_view text, std::vector<protocol::link::Frame> &frames,
                   std::string &why);
  std::string buffer_;
  std::vector<protocol::link::Reply> answers_;
};

} // namespace rsca::control
