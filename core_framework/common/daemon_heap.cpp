#include "common/daemon_heap.hpp"

#include <malloc.h>

namespace rsca {

void bound_daemon_heap() {
  constexpr int kThreshold = 128 * 1024;
  mallopt(M_MMAP_THRESHOLD, kThreshold); // setting it turns off the dynamic raise
  mallopt(M_TRIM_THRESHOLD, kThreshold);
}

HeapTrimmer::HeapTrimmer(std::chrono::milliseconds period) {
  thread_ = std::thread([this, period] {
    std::unique_lock lock(mutex_);
    while (!wake_.wait_for(lock, period, [this] { return stopping_; }))
      malloc_trim(0);
  });
}

HeapTrimmer::~HeapTrimmer() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

} // namespace rsca
