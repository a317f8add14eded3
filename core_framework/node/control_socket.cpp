// The node's control socket (ProcessLinks::listen): local clients connect, each for a link of its
// own over which it makes calls; bounded in number, and in how long one may stay idle.
#include "node/process_links_impl.hpp"

#include <cerrno>
#include <cstring>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/epoll.h>
#include <sys/socket.h>

namespace rsca::node {

void ProcessLinks::Impl::accept_clients() {
  for (;;) {
    process::Fd fd(::accept4(listener_fd.load(), nullptr, nullptr, SOCK_CLOEXEC));
    if (!fd) {
      if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
        if (auto unsaid = refused_log.allow())
          spdlog::warn("control socket {}: accept: {}; clients wait a second{}", listener_path,
                       std::strerror(errno), LogLimiter::unsaid_note(*unsaid));
        pause_accepting();
      } else if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
        if (auto unsaid = refused_log.allow())
          spdlog::warn("control socket {}: accept: {}{}", listener_path, std::strerror(errno),
                       LogLimiter::unsaid_note(*unsaid));
      }
      return;
    }
    ucred peer{};
    socklen_t size = sizeof(peer);
    ::getsockopt(fd.get(), SOL_SOCKET, SO_PEERCRED, &peer, &size);
    auto client = std::make_shared<LinkedProcess>();
    client->pid = peer.pid;
    client->client = true;
    client->writer = std::make_unique<control::LinkWriter>(fd.get());
    const int number = fd.get();
    client->fd = std::move(fd);
    std::lock_guard lock(mutex);
    if (closed || clients >= kMaxClients) {
      if (auto unsaid = refused_log.allow())
        spdlog::warn("control socket {}: a client (pid {}) refused: {} connected already{}",
                     listener_path, peer.pid, clients, LogLimiter::unsaid_note(*unsaid));
      continue; // closed as it goes
    }
    ++clients;
    by_fd[number] = client;
    epoll_event event{};
    event.events = EPOLLIN;
    event.data.fd = number;
    ::epoll_ctl(epoll.get(), EPOLL_CTL_ADD, number, &event);
    spdlog::debug("control socket: client pid {} (uid {}) connected", peer.pid, peer.uid);
  }
}

void ProcessLinks::Impl::drop_idle_clients() {
  const auto now = std::chrono::steady_clock::now();
  std::size_t dropped = 0;
  std::lock_guard lock(mutex);
  for (auto it = by_fd.begin(); it != by_fd.end();) {
    auto &client = *it->second;
    if (!client.client || client.calls.load() > 0 || now - client.heard.load() < kClientIdle) {
      ++it;
      continue;
    }
    ::epoll_ctl(epoll.get(), EPOLL_CTL_DEL, it->first, nullptr);
    --clients;
    end(client, fmt::format("idle for {} s", kClientIdle.count()));
    it = by_fd.erase(it); // its descriptor closes with the last reference to it
    ++dropped;
  }
  if (dropped > 0)
    spdlog::debug("control socket: {} idle client(s) closed", dropped);
}

void ProcessLinks::Impl::pause_accepting() {
  ::epoll_ctl(epoll.get(), EPOLL_CTL_DEL, listener_fd.load(), nullptr);
  accept_paused_until = std::chrono::steady_clock::now() + std::chrono::seconds(1);
}

void ProcessLinks::Impl::resume_accepting() {
  if (accept_paused_until == std::chrono::steady_clock::time_point{} ||
      std::chrono::steady_clock::now() < accept_paused_until)
    return;
  accept_paused_until = {};
  epoll_event event{};
  event.events = EPOLLIN;
  event.data.fd = listener_fd.load();
  ::epoll_ctl(epoll.get(), EPOLL_CTL_ADD, listener_fd.load(), &event);
}

Expected<void> ProcessLinks::listen(const std::string &path) {
  std::lock_guard lock(impl_->mutex);
  if (impl_->listener)
    return make_error({"node", 0, 0}, "control-socket",
                      fmt::format("listening at {} already", impl_->listener_path));
  auto fd = control::listen_for_links(path);
  if (!fd)
    return make_error({"node", 0, 0}, "control-socket", fd.error());
  impl_->listener = std::move(*fd);
  impl_->listener_path = path;
  impl_->listener_fd = impl_->listener.get();
  epoll_event event{};
  event.events = EPOLLIN;
  event.data.fd = impl_->listener.get();
  ::epoll_ctl(impl_->epoll.get(), EPOLL_CTL_ADD, impl_->listener.get(), &event);
  spdlog::info("control socket: local clients connect at {}", path);
  return {};
}

} // namespace rsca::node
