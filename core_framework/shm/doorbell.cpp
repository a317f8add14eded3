#include "shm/doorbell.hpp"

#include <linux/futex.h>
#include <sched.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

namespace rsca::shm {

namespace {

long futex(std::atomic<std::uint32_t> &word, int op, std::uint32_t value, const timespec *timeout) {
  return ::syscall(SYS_futex, reinterpret_cast<std::uint32_t *>(&word), op, value, timeout, nullptr,
                   0);
}

} // namespace

void ring(Doorbell &bell, std::uint32_t why, bool shared) {
  bell.woken.fetch_or(why);
  if (bell.sleeping.load() != 0)
    futex(bell.woken, shared ? FUTEX_WAKE : FUTEX_WAKE_PRIVATE, 1, nullptr);
}

std::uint32_t take(Doorbell &bell) {
  return bell.woken.exchange(0);
}

void sleep(Doorbell &bell, int timeout_ms, bool shared) {
  bell.sleeping.store(1);
  if (bell.woken.load() == 0) {
    const timespec timeout{timeout_ms / 1000, (timeout_ms % 1000) * 1'000'000L};
    // Returns at once if `woken` is no longer 0 (the ring came in between).
    futex(bell.woken, shared ? FUTEX_WAIT : FUTEX_WAIT_PRIVATE, 0,
          timeout_ms < 0 ? nullptr : &timeout);
  }
  bell.sleeping.store(0);
}

std::uint32_t SpinWait::wait(bool after_data, int timeout_ms) {
  if (const auto why = take(bell_); why != 0)
    return why;
  if (after_data && spin_.count() > 0) {
    const auto until = std::chrono::steady_clock::now() + spin_;
    do {
      // Whatever else is runnable on this CPU goes first (on a busy host the ringer itself, or
      // Cyclone's receive thread): the spin takes only a CPU nothing else wants.
      sched_yield();
      // A load first: the word's cache line stays shared with the ringer until it rings.
      if (bell_.woken.load(std::memory_order_relaxed) == 0)
        continue;
      if (const auto why = take(bell_); why != 0) {
        caught_.fetch_add(1, std::memory_order_relaxed);
        return why;
      }
    } while (std::chrono::steady_clock::now() < until);
  }
  sleeps_.fetch_add(1, std::memory_order_relaxed);
  sleep(bell_, timeout_ms, shared_);
  return take(bell_);
}

} // namespace rsca::shm
