#include "shm/doorbell.hpp"

#include <linux/futex.h>
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

} // namespace rsca::shm
