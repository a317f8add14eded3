// How a thread that sleeps until something arrives is woken, from its own process or from
// another: a flag word and a futex on it. In the host's arena (shm/arena.hpp) it is a receive
// thread's doorbell that writers of other processes ring; in private memory the same code runs
// with the cheaper private futex.
//
// Ring: the bits first, then a futex wake only if the thread sleeps (or is about to):
// sequentially consistent, so either the sleeper sees the bits before it waits or the ringer sees
// the sleeper. Never blocks the ringer.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>

namespace rsca::shm {

struct Doorbell {
  std::atomic<std::uint32_t> woken{0};    // bits of why (Wake), or 0: nothing since taken
  std::atomic<std::uint32_t> sleeping{0}; // the thread waits on `woken`
};
static_assert(std::atomic<std::uint32_t>::is_always_lock_free,
              "a doorbell is shared between processes: its words must be lock-free");

// Why a doorbell rang.
enum Wake : std::uint32_t {
  kWakeData = 1u,     // a DDS reader has data (or the owner wants the thread to look)
  kWakeNearData = 2u, // data from this process or host: the thread looks again soon (spins)
};

// `shared`: the doorbell is in memory other processes map (a futex of no process's own).
void ring(Doorbell &bell, std::uint32_t why, bool shared);
// The bits rung since the last take, and clears them.
std::uint32_t take(Doorbell &bell);
// Sleeps until rung or `timeout_ms` passes (negative: no timeout). Returns at once if rung.
void sleep(Doorbell &bell, int timeout_ms, bool shared);

// A thread's wait on its doorbell that, after data, looks again for a bounded while (`spin`,
// yielding the CPU each time) before it sleeps: the next record of a busy exchange then finds it
// awake, which saves the wake (20-40 us on a virtual machine) and the ringer's futex call (ring()
// makes none while the thread is not asleep). Never spins when the last round had no data, so an
// idle thread sleeps. The node's relay thread waits so (node/topic_bridge.cpp).
class SpinWait {
public:
  SpinWait(Doorbell &bell, bool shared, std::chrono::microseconds spin)
      : bell_(bell), shared_(shared), spin_(spin) {}
  // The bits rung: at once if rung since the last take; else, when `after_data`, what rings while
  // it spins; else (or once the spin ends) it sleeps until rung or `timeout_ms` passes (0 bits).
  std::uint32_t wait(bool after_data, int timeout_ms);
  // How many times it slept on the futex, and how many rings it found while spinning (wakes
  // saved): counters for tests and figures, read from any thread.
  std::uint64_t sleeps() const { return sleeps_.load(std::memory_order_relaxed); }
  std::uint64_t caught() const { return caught_.load(std::memory_order_relaxed); }

private:
  Doorbell &bell_;
  bool shared_;
  std::chrono::microseconds spin_;
  std::atomic<std::uint64_t> sleeps_{0}, caught_{0};
};

} // namespace rsca::shm
