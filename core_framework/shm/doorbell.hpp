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

} // namespace rsca::shm
