#include "component/receive_loop.hpp"

#include <poll.h>
#include <sched.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>

#include <fmt/format.h>

namespace rsca::component::detail {
namespace {

// The longest the thread waits before it polls again while watching: the owner then also looks
// for connection problems (component/host.cpp), so this bounds how late a deadline miss is seen.
constexpr int kWakeIntervalMs = 100;

// How long the thread looks for more data before it sleeps: RSCA_RECEIVE_SPIN_US, 50 by default;
// 0 never spins (for a robot that counts every milliwatt more than every microsecond).
std::chrono::microseconds spin_time() {
  static const std::chrono::microseconds spin = [] {
    const char *text = std::getenv("RSCA_RECEIVE_SPIN_US");
    if (text == nullptr || *text == '\0')
      return std::chrono::microseconds{50};
    char *end = nullptr;
    const long value = std::strtol(text, &end, 10);
    return std::chrono::microseconds{*end == '\0' && value >= 0 ? value : 50};
  }();
  return spin;
}

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

void ReceiveLoop::set_watching(bool watching) {
  watching_ = watching;
  wake(); // takes up the new period at once
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

bool ReceiveLoop::take_wake() const {
  std::uint64_t count = 0;
  return ::read(wake_fd_, &count, sizeof count) > 0;
}

void ReceiveLoop::wake_in_host() const {
  in_host_data_.store(true, std::memory_order_release);
  wake();
}

// After in-host data, the thread looks for more for spin_time() before it sleeps: a reply in an
// in-host ping-pong or the next sample of a burst then finds it awake. Waking a sleeping thread
// costs 20-40 us on a virtual machine whose other CPU has gone idle; looking costs a read of the
// eventfd. Not after DDS data: there the spinning threads of many subscribers would take the CPU
// Cyclone needs to deliver (measured: fan-out to 10 processes lost half its rate).
bool ReceiveLoop::spin_for_wake() const {
  const auto until = std::chrono::steady_clock::now() + spin_time();
  while (std::chrono::steady_clock::now() < until) {
    if (take_wake())
      return true;
    // Whatever else is runnable on this CPU goes first: Cyclone's receive thread, which must run
    // before a reply over DDS can arrive, or the other end of an in-host ping-pong.
    sched_yield();
  }
  return false;
}

void ReceiveLoop::run() {
  bool spin = false; // the last round had in-host data
  while (!stopping_.load()) {
    if (!(spin && spin_for_wake())) {
      pollfd fd{wake_fd_, POLLIN, 0};
      if (::poll(&fd, 1, watching_.load() ? kWakeIntervalMs : -1) > 0)
        take_wake();
    }
    spin = in_host_data_.exchange(false, std::memory_order_acq_rel);
    if (stopping_.load())
      return;
    poll_();
  }
}

} // namespace rsca::component::detail
