#include "component/tcp_stream.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <optional>

#include <arpa/inet.h>
#include <fcntl.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <unistd.h>

#include <fmt/format.h>

#include "dds/dds_settings.hpp"

namespace rsca::component::detail {

namespace {

using Clock = std::chrono::steady_clock;

std::string last_error(const char *what) {
  return fmt::format("{}: {}", what, std::strerror(errno));
}

void no_delay(int fd) {
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
}

// "a.b.c.d:port" into an address; nothing else is taken.
std::optional<sockaddr_in> parse_endpoint(const std::string &endpoint) {
  const auto colon = endpoint.rfind(':');
  if (colon == std::string::npos || endpoint.size() > 64)
    return std::nullopt;
  sockaddr_in address{};
  address.sin_family = AF_INET;
  if (::inet_pton(AF_INET, endpoint.substr(0, colon).c_str(), &address.sin_addr) != 1)
    return std::nullopt;
  const std::string port = endpoint.substr(colon + 1);
  if (port.empty() || port.size() > 5 ||
      !std::all_of(port.begin(), port.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return std::nullopt;
  const int number = std::stoi(port);
  if (number <= 0 || number > 65535)
    return std::nullopt;
  address.sin_port = htons(static_cast<std::uint16_t>(number));
  return address;
}

// Waits until `fd` has `events`, the stop eventfd is written, or `deadline` passes (none: no
// deadline). True when `fd` is ready.
bool wait_for(int fd, short events, int stop, std::optional<Clock::time_point> deadline) {
  for (;;) {
    pollfd p[2] = {{fd, events, 0}, {stop, POLLIN, 0}};
    int timeout = -1;
    if (deadline) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(*deadline - Clock::now()).count();
      if (left <= 0)
        return false;
      timeout = static_cast<int>(left);
    }
    const int n = ::poll(p, stop >= 0 ? 2 : 1, timeout);
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0 || (stop >= 0 && (p[1].revents & POLLIN) != 0))
      return false;
    return (p[0].revents & (events | POLLHUP | POLLERR)) != 0;
  }
}

// Reads exactly `bytes` into `at`; false at the end of the stream, an error, the stop, or the
// deadline.
bool read_exactly(int fd, std::byte *at, std::size_t bytes, int stop,
                  std::optional<Clock::time_point> deadline) {
  while (bytes > 0) {
    const ssize_t n = ::recv(fd, at, bytes, MSG_DONTWAIT);
    if (n > 0) {
      at += n;
      bytes -= static_cast<std::size_t>(n);
      continue;
    }
    if (n == 0)
      return false;
    if (errno == EINTR)
      continue;
    if (errno != EAGAIN && errno != EWOULDBLOCK)
      return false;
    if (!wait_for(fd, POLLIN, stop, deadline))
      return false;
  }
  return true;
}

bool read_length(int fd, std::uint32_t &length, int stop,
                 std::optional<Clock::time_point> deadline) {
  std::byte header[4];
  if (!read_exactly(fd, header, sizeof header, stop, deadline))
    return false;
  std::memcpy(&length, header, sizeof length);
  return true;
}

} // namespace

bool valid_token(const std::string &token) {
  return token.size() >= 8 && token.size() <= 64 &&
         std::all_of(token.begin(), token.end(),
                     [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

std::string listen_address() {
  const std::string name = dds::DdsSettings::from_environment().interface_name;
  std::string found = "127.0.0.1";
  ifaddrs *list = nullptr;
  if (name == "lo" || ::getifaddrs(&list) != 0)
    return found;
  for (const ifaddrs *i = list; i != nullptr; i = i->ifa_next) {
    if (i->ifa_addr == nullptr || i->ifa_addr->sa_family != AF_INET || name != i->ifa_name)
      continue;
    char text[INET_ADDRSTRLEN] = {};
    const auto *in = reinterpret_cast<const sockaddr_in *>(i->ifa_addr);
    if (::inet_ntop(AF_INET, &in->sin_addr, text, sizeof text) != nullptr) {
      found = text;
      break;
    }
  }
  ::freeifaddrs(list);
  return found;
}

// ---- the reading end ----------------------------------------------------------------------------

tl::expected<std::unique_ptr<TcpReceiver>, std::string>
TcpReceiver::listen(const std::string &address, std::string token, OnFrame on_frame) {
  if (!valid_token(token))
    return tl::unexpected(std::string("a TCP stream needs a token of 8 to 64 hex digits"));
  auto where = parse_endpoint(address + ":1");
  if (!where)
    return tl::unexpected(fmt::format("\"{}\" is not an IPv4 address", address));
  where->sin_port = 0; // any free port
  process::Fd fd(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
  if (!fd)
    return tl::unexpected(last_error("socket"));
  if (::bind(fd.get(), reinterpret_cast<const sockaddr *>(&*where), sizeof *where) != 0)
    return tl::unexpected(last_error(fmt::format("bind to {}", address).c_str()));
  if (::listen(fd.get(), 4) != 0)
    return tl::unexpected(last_error("listen"));
  sockaddr_in bound{};
  socklen_t length = sizeof bound;
  ::getsockname(fd.get(), reinterpret_cast<sockaddr *>(&bound), &length);
  process::Fd stop(::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK));
  if (!stop)
    return tl::unexpected(last_error("eventfd"));
  const std::string endpoint = fmt::format("{}:{}", address, ntohs(bound.sin_port));
  std::unique_ptr<TcpReceiver> receiver(new TcpReceiver(std::move(fd), std::move(stop), endpoint,
                                                        std::move(token), std::move(on_frame)));
  receiver->thread_ = std::thread([r = receiver.get()] { r->run(); });
  return receiver;
}

TcpReceiver::TcpReceiver(process::Fd listening, process::Fd stop, std::string endpoint,
                         std::string token, OnFrame on_frame)
    : listening_(std::move(listening)), stop_(std::move(stop)), endpoint_(std::move(endpoint)),
      token_(std::move(token)), on_frame_(std::move(on_frame)) {}

TcpReceiver::~TcpReceiver() {
  const std::uint64_t one = 1;
  (void)!::write(stop_.get(), &one, sizeof one);
  if (thread_.joinable())
    thread_.join();
}

void TcpReceiver::run() {
  process::Fd stream = accept_writer();
  if (!stream)
    return;
  // The token admits this writer once: nobody else may connect, now or after it has gone.
  listening_.reset();
  std::fill(token_.begin(), token_.end(), '\0');
  no_delay(stream.get());
  writers_.store(1, std::memory_order_relaxed);
  read_frames(stream.get());
  writers_.store(0, std::memory_order_relaxed);
  spent_.store(true, std::memory_order_relaxed);
}

// The first stream that sends the token; those that do not are closed and counted. An invalid
// descriptor when the receiver is stopped first.
process::Fd TcpReceiver::accept_writer() {
  for (;;) {
    if (!wait_for(listening_.get(), POLLIN, stop_.get(), std::nullopt))
      return process::Fd();
    process::Fd stream(::accept4(listening_.get(), nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK));
    if (!stream)
      continue;
    if (take_token(stream.get()))
      return stream;
    refused_.fetch_add(1, std::memory_order_relaxed);
  }
}

// The first frame is the token, within kTokenTimeout.
bool TcpReceiver::take_token(int fd) {
  const auto deadline = Clock::now() + kTokenTimeout;
  std::uint32_t length = 0;
  if (!read_length(fd, length, stop_.get(), deadline) || length != token_.size())
    return false;
  std::string token(length, '\0');
  return read_exactly(fd, reinterpret_cast<std::byte *>(token.data()), length, stop_.get(),
                      deadline) &&
         token == token_;
}

void TcpReceiver::read_frames(int fd) {
  std::vector<std::byte> frame;
  for (;;) {
    std::uint32_t length = 0;
    if (!read_length(fd, length, stop_.get(), std::nullopt))
      return;
    if (length > kMaxFrame) {
      refused_.fetch_add(1, std::memory_order_relaxed);
      return; // the stream's framing cannot be trusted any more
    }
    frame.resize(length);
    if (!read_exactly(fd, frame.data(), length, stop_.get(), std::nullopt))
      return;
    on_frame_(frame.data(), frame.size());
  }
}

// ---- the writing end ----------------------------------------------------------------------------

tl::expected<std::unique_ptr<TcpSender>, std::string>
TcpSender::connect(const std::string &endpoint, const std::string &token,
                   std::chrono::milliseconds timeout) {
  if (!valid_token(token))
    return tl::unexpected(std::string("a TCP stream needs a token of 8 to 64 hex digits"));
  const auto address = parse_endpoint(endpoint);
  if (!address)
    return tl::unexpected(fmt::format("\"{}\" is not an IPv4 address and port", endpoint));
  process::Fd fd(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
  if (!fd)
    return tl::unexpected(last_error("socket"));
  if (::connect(fd.get(), reinterpret_cast<const sockaddr *>(&*address), sizeof *address) != 0) {
    if (errno != EINPROGRESS)
      return tl::unexpected(last_error(fmt::format("connect to {}", endpoint).c_str()));
    if (!wait_for(fd.get(), POLLOUT, -1, Clock::now() + timeout))
      return tl::unexpected(
          fmt::format("connect to {}: no answer within {} ms", endpoint, timeout.count()));
    int error = 0;
    socklen_t length = sizeof error;
    ::getsockopt(fd.get(), SOL_SOCKET, SO_ERROR, &error, &length);
    if (error != 0)
      return tl::unexpected(fmt::format("connect to {}: {}", endpoint, std::strerror(error)));
  }
  no_delay(fd.get());
  // Blocking from now on, bounded: a reader that stops reading breaks the stream, never the
  // writer's thread for longer than kSendTimeout.
  ::fcntl(fd.get(), F_SETFL, ::fcntl(fd.get(), F_GETFL) & ~O_NONBLOCK);
  const timeval limit{0, static_cast<suseconds_t>(kSendTimeout.count() * 1000)};
  ::setsockopt(fd.get(), SOL_SOCKET, SO_SNDTIMEO, &limit, sizeof limit);
  std::unique_ptr<TcpSender> sender(new TcpSender(std::move(fd)));
  if (auto sent = sender->send(
          token.size(), [&token](std::byte *at) { std::memcpy(at, token.data(), token.size()); });
      !sent)
    return tl::unexpected(sent.error());
  return sender;
}

tl::expected<void, std::string> TcpSender::send(std::size_t bytes,
                                                const std::function<void(std::byte *)> &fill) {
  if (bytes > kMaxFrame)
    return tl::unexpected(fmt::format("a frame of {} bytes is longer than a stream takes", bytes));
  std::lock_guard lock(mutex_);
  if (broken_.load(std::memory_order_relaxed))
    return tl::unexpected(std::string("the TCP stream to the reader is closed"));
  const auto length = static_cast<std::uint32_t>(bytes);
  buffer_.resize(sizeof length + bytes);
  std::memcpy(buffer_.data(), &length, sizeof length);
  fill(buffer_.data() + sizeof length);
  std::size_t sent = 0;
  while (sent < buffer_.size()) {
    const ssize_t n = ::send(fd_.get(), buffer_.data() + sent, buffer_.size() - sent, MSG_NOSIGNAL);
    if (n > 0) {
      sent += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR)
      continue;
    broken_.store(true, std::memory_order_relaxed);
    return tl::unexpected(
        n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)
            ? fmt::format("the reader took nothing for {} ms", kSendTimeout.count())
            : last_error("send"));
  }
  return {};
}

} // namespace rsca::component::detail
