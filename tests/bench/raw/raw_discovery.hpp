// The DDS baseline of a launch (tests/bench/launch_bench.py): N processes forked at once, each a
// bare participant joined as a component process joins, and how long until each has discovered
// all the others (and `existing` participants already there: with N = 1, the join of one more).
// Prints one JSON line; 0 when every one of them settled within `timeout_ms`. Stops early when
// `stop` is set (SIGTERM).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>

namespace rsca::bench::raw {

int discovery(std::size_t participants, std::size_t existing, std::uint64_t timeout_ms,
              const std::atomic<bool> &stop);

} // namespace rsca::bench::raw
