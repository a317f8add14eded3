#include "common/daemon_heap.hpp"

#include <malloc.h>

namespace rsca {

void bound_daemon_heap() {
  constexpr int kThreshold = 128 * 1024;
  mallopt(M_MMAP_THRESHOLD, kThreshold); // setting it turns off the dynamic raise
  mallopt(M_TRIM_THRESHOLD, kThreshold);
}

HeapTrimmer::HeapTrimmer(std::chrono::milliseconds period)
    : trim_(period, [] { malloc_trim(0); }) {}

} // namespace rsca
