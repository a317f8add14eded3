// Waiting for a condition on real processes in tests: polled at a pace, bounded, checked once
// more at the deadline. Shared by the integration and multihost fixtures.
#pragma once

#include <chrono>
#include <thread>

namespace rsca::test {

template <typename Predicate>
bool wait_until(Predicate done, std::chrono::milliseconds limit,
                std::chrono::milliseconds pace = std::chrono::milliseconds(20)) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < deadline) {
    if (done())
      return true;
    std::this_thread::sleep_for(pace); // pacing a poll of real processes
  }
  return done();
}

} // namespace rsca::test
