#include "component/receive_loop.hpp"

#include <sched.h>

#include <chrono>

#include "common/env_duration.hpp"
#include "shm/process_arena.hpp"

namespace rsca::component::detail {
namespace {

// The longest the thread waits before it polls again while watching: the owner then also looks
// for connection problems (component/host.cpp), so this bounds how late a deadline miss is seen.
constexpr int kWakeIntervalMs = 100;

// How long the thread looks for more data before it sleeps: RSCA_RECEIVE_SPIN_US, 50 by default;
// 0 never spins (for a robot that counts every milliwatt more than every microsecond).
std::chrono::microseconds spin_time() {
  static const std::chrono::microseconds spin =
      microseconds_from_env("RSCA_RECEIVE_SPIN_US", std::chrono::microseconds{50});
  return spin;
}

} // namespace

Expected<std::unique_ptr<ReceiveLoop>> ReceiveLoop::start(std::function<void()> poll,
                                                          std::recursive_mutex *owner_lock) {
  std::unique_ptr<ReceiveLoop> loop(new ReceiveLoop(std::move(poll), owner_lock));
  loop->thread_ = std::thread([raw = loop.get()] { raw->run(); });
  return loop;
}

ReceiveLoop::ReceiveLoop(std::function<void()> poll, std::recursive_mutex *owner_lock)
    : listener_(dds_create_listener(this)), poll_(std::move(poll)), owner_lock_(owner_lock) {
  dds_lset_data_available(listener_, &ReceiveLoop::on_data_available);
  if (auto *arena = shm::ProcessArena::inherited())
    if (auto *bell = arena->allocate_doorbell()) {
      bell_ = bell;
      doorbell_offset_ = arena->arena().offset_of(bell);
    }
}

ReceiveLoop::~ReceiveLoop() {
  stop();
  dds_delete_listener(listener_);
  if (doorbell_offset_)
    shm::ProcessArena::inherited()->release_doorbell(bell_);
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

bool &ReceiveLoop::delivering_on_this_thread() {
  thread_local bool delivering = false;
  return delivering;
}

void ReceiveLoop::wake() const {
  shm::ring(*bell_, shm::kWakeData, doorbell_offset_.has_value());
}

std::uint32_t ReceiveLoop::take_wake() const {
  return shm::take(*bell_);
}

void ReceiveLoop::sleep_until_woken(int timeout_ms) const {
  shm::sleep(*bell_, timeout_ms, doorbell_offset_.has_value());
}

void ReceiveLoop::wake_in_host() const {
  shm::ring(*bell_, shm::kWakeNearData, doorbell_offset_.has_value());
}

// After in-host or same-host data, the thread looks for more for spin_time() before it sleeps: a
// reply in an in-host ping-pong or the next sample of a burst then finds it awake. Waking a
// sleeping thread costs 20-40 us on a virtual machine whose other CPU has gone idle; looking costs
// a read of the flag. Not after DDS data: there the spinning threads of many subscribers would take
// the CPU Cyclone needs to deliver (measured: fan-out to 10 processes lost half its rate).
std::uint32_t ReceiveLoop::spin_for_wake() const {
  const auto until = std::chrono::steady_clock::now() + spin_time();
  while (std::chrono::steady_clock::now() < until) {
    if (auto why = take_wake(); why != 0)
      return why;
    // Whatever else is runnable on this CPU goes first: Cyclone's receive thread, which must run
    // before a reply over DDS can arrive, or the other end of an in-host ping-pong.
    sched_yield();
  }
  return 0;
}

void ReceiveLoop::run() {
  std::uint32_t why = 0; // what woke the last round
  while (!stopping_.load()) {
    const bool spin = (why & shm::kWakeNearData) != 0;
    why = spin ? spin_for_wake() : take_wake();
    if (why == 0) {
      sleep_until_woken(watching_.load() ? kWakeIntervalMs : -1);
      why = take_wake();
    }
    if (stopping_.load())
      return;
    std::lock_guard one_at_a_time(delivery_); // a listener's delivery under way ends first
    bool &marked = delivering_on_this_thread();
    marked = true;
    poll_();
    marked = false;
  }
}

} // namespace rsca::component::detail
