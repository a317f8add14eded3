// Waiting in a test for a condition another thread or process makes true: polled, bounded, so
// that what never comes fails the test instead of stalling it (a hang guard, not a measure of
// speed).
#pragma once

#include <chrono>
#include <functional>
#include <thread>

namespace rsca::test {

inline bool eventually(const std::function<bool()> &condition,
                       std::chrono::milliseconds limit = std::chrono::seconds(30)) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (!condition()) {
    if (std::chrono::steady_clock::now() > deadline)
      return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1)); // pacing the poll of a condition
  }
  return true;
}

} // namespace rsca::test
