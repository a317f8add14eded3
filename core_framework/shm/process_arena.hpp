// A process's side of its host's arena (shm/arena.hpp): the arena it inherited from its node,
// and its own page, where the doorbells of its receive threads are. Mapped once, at first use;
// a process its node did not start (run by hand, in a test) has none, and its connections to
// other processes go over DDS.
#pragma once

#include <cstdint>
#include <mutex>
#include <vector>

#include "shm/arena.hpp"
#include "shm/doorbell.hpp"

namespace rsca::shm {

class ProcessArena {
public:
  // This process's, from kArenaVariable; null when it has none (or it cannot be mapped: said
  // once in the log).
  static ProcessArena *inherited();

  ProcessArena(Arena arena, std::uint64_t page, std::uint64_t page_bytes);
  const Arena &arena() const { return arena_; }
  // A doorbell of this process's page, a cache line of its own; null when all are taken.
  Doorbell *allocate_doorbell();
  void release_doorbell(Doorbell *bell);

private:
  Arena arena_;
  std::mutex mutex_;
  std::vector<std::uint64_t> free_; // offsets of doorbells not in use
};

} // namespace rsca::shm
