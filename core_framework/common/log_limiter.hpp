// A warning said at most once per interval, with how many like it were left unsaid meanwhile: a
// flood of one event (hostile clients by the thousand) writes a line per interval, not a line per
// event, and the count still says how many there were (issue 37, defect 11).
//
//   static LogLimiter refusals;
//   if (auto unsaid = refusals.allow())
//     spdlog::warn("a client refused{}", LogLimiter::unsaid_note(*unsaid));
#pragma once

#include <chrono>
#include <cstddef>
#include <mutex>
#include <optional>
#include <string>

#include <fmt/format.h>

namespace rsca {

class LogLimiter {
public:
  using Clock = std::chrono::steady_clock;

  explicit LogLimiter(Clock::duration interval = std::chrono::seconds(10)) : interval_(interval) {}

  // The number of events held back since the last line said, when this one is to be said now;
  // nothing when it is to be held back (counted).
  std::optional<std::size_t> allow(Clock::time_point now = Clock::now()) {
    std::lock_guard lock(mutex_);
    if (said_ && now - *said_ < interval_) {
      ++unsaid_;
      return std::nullopt;
    }
    said_ = now;
    const std::size_t unsaid = unsaid_;
    unsaid_ = 0;
    return unsaid;
  }

  // " (N more like it since the last such line)" for a line that follows held-back ones, else
  // nothing.
  static std::string unsaid_note(std::size_t unsaid) {
    return unsaid == 0 ? std::string()
                       : fmt::format(" ({} more like it since the last such line)", unsaid);
  }

private:
  const Clock::duration interval_;
  std::mutex mutex_;
  std::optional<Clock::time_point> said_;
  std::size_t unsaid_ = 0;
};

} // namespace rsca
