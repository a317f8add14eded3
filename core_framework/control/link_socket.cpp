#include "control/link_socket.hpp"

#include <cerrno>
#include <cstring>
#include <utility>

#include <fcntl.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/un.h>
#include <unistd.h>

#include "protocol/json_text.hpp"

namespace rsca::control {

namespace link = protocol::link;
using protocol::Json;

namespace {
// A frame's body sits two levels down ({"request": {"body": …}}): the bound is the body's.
constexpr std::size_t kFrameDepth = protocol::kMaxJsonDepth + 2;
} // namespace

protocol::CallResult<nlohmann::json> reply_result(const link::Reply &reply) {
  using protocol::call_error;
  using protocol::Status;
  if (reply.status == static_cast<std::int32_t>(Status::Ok))
    return reply.body;
  // A status this version does not know is a failure all the same, said as it came.
  auto error =
      protocol::is_known(reply.status)
          ? call_error(static_cast<Status>(reply.status), reply.error)
          : call_error(Status::Failed, fmt::format("status {}: {}", reply.status, reply.error));
  error.value().details = protocol::details_of(reply.body);
  error.value().maybe_received = protocol::maybe_received_of(reply.body);
  return error;
}

link::Reply link_reply(const std::string &id, const protocol::CallResult<nlohmann::json> &result) {
  if (result)
    return {id, 0, "", *result};
  return {id, static_cast<std::int32_t>(result.error().status), result.error().message,
          protocol::error_body_json(result.error())};
}

tl::expected<std::pair<process::Fd, process::Fd>, std::string> make_link_pair() {
  int fds[2] = {-1, -1};
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0)
    return tl::unexpected(fmt::format("socketpair: {}", std::strerror(errno)));
  return std::pair{process::Fd(fds[0]), process::Fd(fds[1])};
}

namespace {

// A non-blocking Unix stream socket and the address of `path`, for listening or connecting.
struct UnixSocket {
  process::Fd fd;
  sockaddr_un address{};
};

tl::expected<UnixSocket, std::string> unix_socket(const std::string &path) {
  UnixSocket s;
  s.address.sun_family = AF_UNIX;
  if (path.empty() || path.size() >= sizeof(s.address.sun_path))
    return tl::unexpected(fmt::format("\"{}\" cannot name a Unix socket (1 to {} bytes)", path,
                                      sizeof(s.address.sun_path) - 1));
  std::memcpy(s.address.sun_path, path.data(), path.size());
  s.fd = process::Fd(::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
  if (!s.fd)
    return tl::unexpected(fmt::format("socket: {}", std::strerror(errno)));
  return s;
}

// 0 once connected, else errno.
int connect_to(const UnixSocket &s) {
  return ::connect(s.fd.get(), reinterpret_cast<const sockaddr *>(&s.address), sizeof(s.address)) ==
                 0
             ? 0
             : errno;
}

} // namespace

namespace detail {

tl::expected<process::Fd, std::string> bind_unix_socket(const std::string &path, mode_t mode) {
  auto s = unix_socket(path);
  if (!s)
    return tl::unexpected(s.error());
  // Linux makes the socket file with the socket's own mode less the umask: set before bind, the
  // file is never more open than `mode`.
  ::fchmod(s->fd.get(), mode);
  if (::bind(s->fd.get(), reinterpret_cast<const sockaddr *>(&s->address), sizeof(s->address)) != 0)
    return tl::unexpected(fmt::format("bind {}: {}", path, std::strerror(errno)));
  return std::move(s->fd);
}

} // namespace detail

tl::expected<process::Fd, std::string> listen_for_links(const std::string &path) {
  // A socket file nobody accepts on was left by a node that died: replaced. One that accepts is
  // another's.
  if (auto probe = unix_socket(path)) {
    const int error = connect_to(*probe);
    if (error == 0)
      return tl::unexpected(fmt::format("{}: another process listens there", path));
    if (error == ECONNREFUSED)
      ::unlink(path.c_str());
  }
  auto fd = detail::bind_unix_socket(path, 0660);
  if (!fd)
    return fd;
  ::chmod(path.c_str(), 0660); // exactly, whatever the umask took
  if (::listen(fd->get(), 64) != 0)
    return tl::unexpected(fmt::format("listen {}: {}", path, std::strerror(errno)));
  return fd;
}

tl::expected<process::Fd, std::string> connect_link(const std::string &path) {
  // Non-blocking while connecting: a node whose backlog is full refuses (EAGAIN) instead of
  // holding the caller; blocking again afterwards, as LinkWriter expects.
  auto s = unix_socket(path);
  if (!s)
    return tl::unexpected(s.error());
  if (const int error = connect_to(*s); error != 0)
    return tl::unexpected(fmt::format("connect {}: {}", path, std::strerror(error)));
  ::fcntl(s->fd.get(), F_SETFL, ::fcntl(s->fd.get(), F_GETFL) & ~O_NONBLOCK);
  return std::move(s->fd);
}

std::string wire_of(std::string_view text) {
  const auto size = static_cast<std::uint32_t>(text.size());
  std::string wire;
  wire.reserve(4 + text.size());
  for (int shift = 24; shift >= 0; shift -= 8)
    wire.push_back(static_cast<char>((size >> static_cast<unsigned>(shift)) & 0xffU));
  wire += text;
  return wire;
}

LinkWriter::LinkWriter(int fd, std::chrono::milliseconds timeout) : fd_(fd) {
  timeval tv{};
  tv.tv_sec = static_cast<time_t>(timeout.count() / 1000);
  tv.tv_usec = static_cast<suseconds_t>((timeout.count() % 1000) * 1000);
  ::setsockopt(fd_, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof(tv));
}

tl::expected<void, std::string> LinkWriter::send(const link::Frame &frame) {
  std::string text;
  try {
    text = link::encode_frame(frame).dump();
  } catch (const nlohmann::json::exception &e) { // a string that is not UTF-8
    return tl::unexpected(fmt::format("a frame the link cannot carry: {}", e.what()));
  }
  if (text.size() > link::kMaxLinkFrame)
    return tl::unexpected(fmt::format("a frame of {} bytes is over the link's limit of {}",
                                      text.size(), link::kMaxLinkFrame));
  const std::string wire = wire_of(text);
  std::lock_guard lock(mutex_);
  std::size_t sent = 0;
  while (sent < wire.size()) {
    const ssize_t n = ::send(fd_, wire.data() + sent, wire.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR)
      continue;
    if (n < 0) {
      const int error = errno;
      // Part of a frame went: the stream is cut mid-frame and no later frame could be read, so
      // the link ends here, for both sides.
      if (sent > 0)
        ::shutdown(fd_, SHUT_RDWR);
      return tl::unexpected(error == EAGAIN || error == EWOULDBLOCK
                                ? std::string("the peer does not read its link")
                                : fmt::format("send: {}", std::strerror(error)));
    }
    sent += static_cast<std::size_t>(n);
  }
  return {};
}

bool FrameReader::read_from(int fd, std::vector<link::Frame> &frames, std::string &why) {
  char chunk[64 * 1024];
  const ssize_t n = ::recv(fd, chunk, sizeof(chunk), MSG_DONTWAIT);
  if (n < 0 && (errno == EINTR || errno == EAGAIN))
    return true;
  if (n < 0) {
    why = fmt::format("recv: {}", std::strerror(errno));
    return false;
  }
  if (n == 0) {
    why = "the link was closed";
    return false;
  }
  buffer_.append(chunk, static_cast<std::size_t>(n));
  return cut(frames, why);
}

bool FrameReader::cut(std::vector<link::Frame> &frames, std::string &why) {
  std::size_t at = 0;
  while (buffer_.size() - at >= 4) {
    std::uint32_t size = 0;
    for (std::size_t i = 0; i < 4; ++i)
      size = (size << 8U) | static_cast<unsigned char>(buffer_[at + i]);
    if (size > link::kMaxLinkFrame) {
      why = fmt::format("a frame of {} bytes is over the link's limit of {}", size,
                        link::kMaxLinkFrame);
      return false;
    }
    if (buffer_.size() - at - 4 < size)
      break;
    const std::string_view text(buffer_.data() + at + 4, size);
    at += 4 + size;
    auto json = protocol::parse_json(text, kFrameDepth);
    if (!json && protocol::nests_deeper(text, kFrameDepth)) {
      if (!refuse_deep(text, frames, why))
        return false;
      continue;
    }
    if (!json) {
      why = fmt::format("a frame is {}", json.error());
      return false;
    }
    auto frame = link::decode_frame(*json);
    if (!frame) {
      why = frame.error();
      return false;
    }
    frames.push_back(std::move(*frame));
  }
  buffer_.erase(0, at);
  return true;
}

bool FrameReader::refuse_deep(std::string_view text, std::vector<link::Frame> &frames,
                              std::string &why) {
  auto frame = link::decode_frame(protocol::parse_json_pruned(text, kFrameDepth));
  if (!frame) {
    why = frame.error();
    return false;
  }
  const std::string what =
      fmt::format("the body nests deeper than {} levels", protocol::kMaxJsonDepth);
  if (const auto *request = std::get_if<link::Request>(&*frame)) {
    answers_.push_back(
        link_reply(request->id, protocol::call_error(protocol::Status::BadRequest,
                                                     fmt::format("{} to {}: {}", request->operation,
                                                                 request->target, what))));
  } else if (const auto *reply = std::get_if<link::Reply>(&*frame)) {
    frames.emplace_back(link::Reply{reply->id,
                                    static_cast<std::int32_t>(protocol::Status::BadRequest),
                                    fmt::format("a reply refused: {}", what), Json::object()});
  } else {
    spdlog::warn("a link's frame refused: {}", what);
  }
  return true;
}

std::vector<link::Reply> FrameReader::answers() {
  return std::exchange(answers_, {});
}

} // namespace rsca::control
