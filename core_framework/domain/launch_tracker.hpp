// The launches the ApplicationFactory is running and the last ones it finished, by the id their
// caller gave: what app.progress reports and what app.cancel reaches. A caller's cancel travels
// apart from its create and may overtake it; it is kept, and that launch then never begins.
#pragma once

#include <atomic>
#include <cstddef>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "domain/application_factory.hpp"

namespace rsca::domain {

class LaunchTracker {
public:
  // How many finished launches stay known: long enough for a caller's last look at its progress,
  // bounded so that a daemon that runs for months does not keep every launch it ever ran.
  static constexpr std::size_t kKeptFinished = 64;

  // Starts tracking launch `id`; the flag it returns is set when the launch is cancelled. Null
  // when a cancel for `id` came first: the launch must not begin.
  std::shared_ptr<const std::atomic<bool>> begin(const std::string &id);
  void record(const std::string &id, const LaunchStep &step);
  // Ends launch `id`. False when it launched but was cancelled meanwhile: the caller was told it
  // would not run, so it must be released and finished again as not launched.
  bool finish(const std::string &id, bool launched);

  struct Progress {
    std::vector<LaunchStep> steps;
    bool done = false;
  };
  std::optional<Progress> progress(const std::string &id) const;

  struct Cancelled {
    bool cancelled = false; // false: it had finished
    bool done = false;
    bool begun = true; // false: not seen yet (its create may still come, and is then refused)
  };
  Cancelled cancel(const std::string &id);

  // Remembers a launch that failed after starting processes: the last FailedLaunch::kKept, so
  // that the logs of their rolled-back components stay reachable (app.failed).
  void failed(protocol::application::FailedLaunch launch);
  // Those of `application` (all when absent), oldest first.
  std::vector<protocol::application::FailedLaunch>
  failures(const std::optional<std::string> &application) const;

private:
  struct Launch {
    Progress progress;
    std::shared_ptr<std::atomic<bool>> cancelled = std::make_shared<std::atomic<bool>>(false);
  };
  void retire(const std::string &id); // under mutex_

  mutable std::mutex mutex_;
  std::map<std::string, Launch> launches_;
  std::deque<std::string> finished_;                       // oldest first
  std::deque<protocol::application::FailedLaunch> failed_; // oldest first
};

} // namespace rsca::domain
