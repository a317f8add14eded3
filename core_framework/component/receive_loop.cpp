#include "component/receive_loop.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <fmt/format.h>

namespace rsca::component::detail {
namespace {

// The longest the thread waits before it polls again: the owner then also looks for connection
// problems (component/host.cpp), so this bounds how late a deadline miss is seen.
constexpr int kWakeIntervalMs = 100;

} // namespace

Expected<std::unique_ptr<ReceiveLoop>> ReceiveLoop::start(std::function<void()> poll) {
  const int fd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (fd < 0)
    return make_error({"receive loop", 0, 0}, "dds",
                      fmt::format("eventfd: {}", std::strerror(errno)));
  std::unique_ptr<ReceiveLoop> loop(new ReceiveLoop(fd, std::move(poll)));
  loop->thread_ = std::thread([raw = loop.get()] { raw->run(); });
  return loop;
}

ReceiveLoop::ReceiveLoop(int wake_fd, std::function<void()> poll)
    : wake_fd_(wake_fd), listener_(dds_create_listener(this)), poll_(std::move(poll)) {
  dds_lset_data_available(listener_, &ReceiveLoop::on_data_available);
}

ReceiveLoop::~ReceiveLoop() {
  stop();
  dds_delete_listener(listener_);
  ::close(wake_fd_);
}

void ReceiveLoop::stop() {
  stopping_ = true;
  wake();
  if (thread_.joinable())
    thread_.join();
}

Expected<void> ReceiveLoop::attach(dds_entity_t reader) {
  if (dds_return_t rc = dds_set_listener(reader, listener_); rc < 0)
    return tl::unexpected(dds::dds_error(rc, "setting a reader's listener"));
  wake(); // what arrived before the listener was set
  return {};
}

void ReceiveLoop::detach(dds_entity_t reader) {
  dds_set_listener(reader, nullptr);
}

void ReceiveLoop::on_data_available(dds_entity_t, void *loop) {
  static_cast<const ReceiveLoop *>(loop)->wake();
}

void ReceiveLoop::wake() const {
  const std::uint64_t one = 1;
  [[maybe_unused]] auto n = ::write(wake_fd_, &one, sizeof one);
}

void ReceiveLoop::run() {
  while (!stopping_.load()) {
    pollfd fd{wake_fd_, POLLIN, 0};
    if (::poll(&fd, 1, kWakeIntervalMs) > 0) {
      std::uint64_t count = 0;
      [[maybe_unused]] auto n = ::read(wake_fd_, &count, sizeof count);
    }
    if (stopping_.load())
      return;
    poll_();
  }
}

} // namespace rsca::component::detail
