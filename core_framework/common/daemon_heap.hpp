// A daemon's heap over months of launches, releases and commands. With glibc's defaults its
// resident memory grew by ~15 KB a launch/release cycle, most of it memory the daemon had freed
// (issue 18, defect 5): each time a large block (a Cyclone receive buffer, a long JSON reply) is
// freed, glibc raises its mmap threshold, so later large blocks come from the heap, which fragments
// and is given back only from its top. So the daemons fix the thresholds (large blocks keep
// mappings of their own, returned when freed) and give free pages back now and then (malloc_trim:
// also those inside the heap): ~3 KB a cycle. Figures: docs/measurements.md, `tools/bench soak`.
#pragma once

#include <chrono>

#include "common/periodic.hpp"

namespace rsca {

// Fixes malloc's mmap and trim thresholds at 128 KiB (its initial values, no longer raised). First
// in a daemon's main.
void bound_daemon_heap();

// For its lifetime, gives the heap's free pages back to the system every `period` (malloc_trim on
// a thread of its own: a pass over the arenas, well under a millisecond for a daemon's heap).
class HeapTrimmer {
public:
  explicit HeapTrimmer(std::chrono::milliseconds period = std::chrono::seconds(5));
  HeapTrimmer(const HeapTrimmer &) = delete;
  HeapTrimmer &operator=(const HeapTrimmer &) = delete;

private:
  Periodic trim_;
};

} // namespace rsca
