// The service manager's side of sd_notify(3), for tests: a Unix datagram socket the test owns,
// named to a daemon as NOTIFY_SOCKET, whose messages it receives with the sender's pid (as systemd
// does, to accept only the main process's with NotifyAccess=main). Also used for a stand-in of
// journald's socket (journal_test.cpp): the same kind of socket.
#pragma once

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <catch2/catch.hpp>

#include "process/fd.hpp"

namespace rsca::test {

class DatagramSocket {
public:
  struct Message {
    pid_t pid = 0; // the sender's, from its credentials
    std::string text;
  };

  // Bound at `path` (its folder must exist), with SO_PASSCRED so each message carries its sender.
  explicit DatagramSocket(std::filesystem::path path) : path_(std::move(path)) {
    fd_ = process::Fd(::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0));
    REQUIRE(fd_);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    REQUIRE(path_.string().size() < sizeof(address.sun_path));
    std::memcpy(address.sun_path, path_.c_str(), path_.string().size());
    REQUIRE(::bind(fd_.get(), reinterpret_cast<const sockaddr *>(&address), sizeof(address)) == 0);
    const int on = 1;
    REQUIRE(::setsockopt(fd_.get(), SOL_SOCKET, SO_PASSCRED, &on, sizeof(on)) == 0);
    // Room for a daemon's start-up logs (journal_test.cpp) while the test waits elsewhere.
    const int buffer = 4 << 20;
    ::setsockopt(fd_.get(), SOL_SOCKET, SO_RCVBUF, &buffer, sizeof(buffer));
  }
  ~DatagramSocket() { ::unlink(path_.c_str()); }
  DatagramSocket(const DatagramSocket &) = delete;
  DatagramSocket &operator=(const DatagramSocket &) = delete;

  const std::filesystem::path &path() const { return path_; }

  // The next message, or nothing within `timeout`.
  std::optional<Message> receive(std::chrono::milliseconds timeout) {
    pollfd p{fd_.get(), POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(timeout.count())) != 1)
      return std::nullopt;
    std::vector<char> data(1 << 20);
    iovec io{data.data(), data.size()};
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(ucred))] = {};
    msghdr header{};
    header.msg_iov = &io;
    header.msg_iovlen = 1;
    header.msg_control = control;
    header.msg_controllen = sizeof(control);
    const ssize_t n = ::recvmsg(fd_.get(), &header, MSG_CMSG_CLOEXEC);
    if (n < 0)
      return std::nullopt;
    Message m{0, std::string(data.data(), static_cast<std::size_t>(n))};
    for (cmsghdr *c = CMSG_FIRSTHDR(&header); c != nullptr; c = CMSG_NXTHDR(&header, c))
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_CREDENTIALS) {
        ucred credentials{};
        std::memcpy(&credentials, CMSG_DATA(c), sizeof(credentials));
        m.pid = credentials.pid;
      }
    return m;
  }

  // Receives until a message satisfies `wanted`, for at most `limit`; every message received is
  // kept in `received()`. The message, or nothing.
  template <typename Predicate>
  std::optional<Message> wait_for(Predicate wanted, std::chrono::milliseconds limit) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    for (;;) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0)
        return std::nullopt;
      auto m = receive(left);
      if (!m)
        return std::nullopt;
      received_.push_back(*m);
      if (wanted(*m))
        return m;
    }
  }

  const std::vector<Message> &received() const { return received_; }

private:
  std::filesystem::path path_;
  process::Fd fd_;
  std::vector<Message> received_;
};

// Whether a notification (newline-separated assignments) holds `assignment` ("READY=1").
inline bool assigns(const DatagramSocket::Message &m, std::string_view assignment) {
  std::string_view rest = m.text;
  while (!rest.empty()) {
    const auto end = rest.find('\n');
    if (rest.substr(0, end) == assignment)
      return true;
    if (end == std::string_view::npos)
      break;
    rest.remove_prefix(end + 1);
  }
  return false;
}

// The value of `name` in a notification ("STATUS"), or empty.
inline std::string value_of(const DatagramSocket::Message &m, std::string_view name) {
  const std::string key = std::string(name) + "=";
  std::string_view rest = m.text;
  while (!rest.empty()) {
    const auto end = rest.find('\n');
    const auto line = rest.substr(0, end);
    if (line.substr(0, key.size()) == key)
      return std::string(line.substr(key.size()));
    if (end == std::string_view::npos)
      break;
    rest.remove_prefix(end + 1);
  }
  return {};
}

} // namespace rsca::test
