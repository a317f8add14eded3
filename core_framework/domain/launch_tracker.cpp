#include "domain/launch_tracker.hpp"

namespace rsca::domain {

std::shared_ptr<const std::atomic<bool>> LaunchTracker::begin(const std::string &id) {
  std::lock_guard lock(mutex_);
  auto it = launches_.find(id);
  if (it != launches_.end() && it->second.cancelled->load() && !it->second.progress.done) {
    it->second.progress.done = true; // the cancel that came first is answered
    return nullptr;
  }
  launches_[id] = Launch{};
  return launches_[id].cancelled;
}

void LaunchTracker::record(const std::string &id, const LaunchStep &step) {
  std::lock_guard lock(mutex_);
  if (auto it = launches_.find(id); it != launches_.end())
    it->second.progress.steps.push_back(step);
}

bool LaunchTracker::finish(const std::string &id, bool launched) {
  std::lock_guard lock(mutex_);
  auto it = launches_.find(id);
  if (it == launches_.end())
    return true;
  // Under the mutex: a cancel either finds the launch done (and says so) or is seen here.
  if (launched && it->second.cancelled->load())
    return false;
  it->second.progress.done = true;
  retire(id);
  return true;
}

std::optional<LaunchTracker::Progress> LaunchTracker::progress(const std::string &id) const {
  std::lock_guard lock(mutex_);
  auto it = launches_.find(id);
  if (it == launches_.end())
    return std::nullopt;
  return it->second.progress;
}

LaunchTracker::Cancelled LaunchTracker::cancel(const std::string &id) {
  std::lock_guard lock(mutex_);
  auto [it, first] = launches_.try_emplace(id);
  if (it->second.progress.done)
    return {false, true};
  it->second.cancelled->store(true);
  if (first)
    retire(id); // a launch that may never come: bounded like the finished ones
  return {true, false, !first};
}

void LaunchTracker::failed(protocol::application::FailedLaunch launch) {
  std::lock_guard lock(mutex_);
  failed_.push_back(std::move(launch));
  while (failed_.size() > protocol::application::FailedLaunch::kKept)
    failed_.pop_front();
}

std::vector<protocol::application::FailedLaunch>
LaunchTracker::failures(const std::optional<std::string> &application) const {
  std::lock_guard lock(mutex_);
  std::vector<protocol::application::FailedLaunch> out;
  for (const auto &f : failed_)
    if (!application || f.application == *application)
      out.push_back(f);
  return out;
}

void LaunchTracker::retire(const std::string &id) {
  finished_.push_back(id);
  while (finished_.size() > kKeptFinished) {
    // A caller that reused an id may have begun it again: that launch stays, unless cancelled.
    if (auto it = launches_.find(finished_.front());
        it != launches_.end() && (it->second.progress.done || it->second.cancelled->load()))
      launches_.erase(it);
    finished_.pop_front();
  }
}

} // namespace rsca::domain
