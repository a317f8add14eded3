#include "component/liveliness_ticker.hpp"

#include <algorithm>

namespace rsca::component::detail {

LivelinessTicker &LivelinessTicker::instance() {
  static LivelinessTicker ticker;
  return ticker;
}

LivelinessTicker::~LivelinessTicker() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable())
    thread_.join();
}

void LivelinessTicker::add(shm::RingWriter *writer, std::chrono::nanoseconds lease) {
  writer->assert_alive();
  {
    std::lock_guard lock(mutex_);
    writers_[writer] = lease;
    if (!thread_.joinable())
      thread_ = std::thread([this] { run(); });
  }
  changed_.notify_all(); // a shorter lease is taken up at once
}

void LivelinessTicker::remove(shm::RingWriter *writer) {
  std::lock_guard lock(mutex_);
  writers_.erase(writer);
}

void LivelinessTicker::run() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    if (writers_.empty()) {
      changed_.wait(lock, [this] { return stopping_ || !writers_.empty(); });
      continue;
    }
    auto shortest = std::chrono::nanoseconds::max();
    for (const auto &[writer, lease] : writers_) {
      writer->assert_alive();
      shortest = std::min(shortest, lease);
    }
    changed_.wait_for(lock, shortest / 3);
  }
}

} // namespace rsca::component::detail
