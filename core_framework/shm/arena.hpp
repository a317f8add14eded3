// The host's data arena: one shared memory file that a node makes and every process it starts
// maps, inherited as a known descriptor. The rings of same-host connections (shm/ring.hpp) and
// the doorbells of the processes' receive threads (shm/doorbell.hpp) live in it, named by their
// offset: a pointer means nothing in another process. The node alone allocates in it
// (ArenaAllocator); a process only uses what the node gave it, and checks every offset it is
// given against the arena's bounds.
//
// Why not iceoryx 2.0.3 (Debian's): its RouDi is one per machine (a fixed lock name, socket
// and segment names compiled in, no domain id), at most 300 processes, so several nodes of
// one machine (`rsca domain up --nodes N`, the tests, each with its own domain) cannot each
// own one, and 500 processes on 10 nodes of one machine exceed it (docs/architecture.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "common/diagnostic.hpp"
#include "process/fd.hpp"

namespace rsca::shm {

// The descriptor a process started by its node finds the arena at, and the variable that says
// so and where the process's own page is: "<fd>:<page offset>:<page bytes>".
inline constexpr int kArenaFd = 4;
inline constexpr const char *kArenaVariable = "RSCA_HOST_ARENA";

class Arena {
public:
  // A new arena of `bytes` (memory is taken only as it is touched): the node's.
  static Expected<Arena> create(std::size_t bytes);
  // The arena behind `fd`, its size the file's: a process's, from its node.
  static Expected<Arena> map(process::Fd fd);

  Arena(Arena &&other) noexcept;
  Arena &operator=(Arena &&other) noexcept;
  Arena(const Arena &) = delete;
  Arena &operator=(const Arena &) = delete;
  ~Arena();

  // `bytes` at `offset`; nullptr unless all of them are inside the arena.
  std::byte *at(std::uint64_t offset, std::size_t bytes) const;
  template <typename T>
  T *object(std::uint64_t offset) const {
    if (offset % alignof(T) != 0)
      return nullptr;
    return reinterpret_cast<T *>(at(offset, sizeof(T)));
  }
  // The offset of `p`, which must point into the arena.
  std::uint64_t offset_of(const void *p) const {
    return static_cast<std::uint64_t>(static_cast<const std::byte *>(p) - base_);
  }
  int fd() const { return fd_.get(); }
  std::size_t size() const { return size_; }

private:
  Arena(process::Fd fd, std::byte *base, std::size_t size)
      : fd_(std::move(fd)), base_(base), size_(size) {}
  process::Fd fd_;
  std::byte *base_ = nullptr;
  std::size_t size_ = 0;
};

// The node's bookkeeping of what is in use in its arena: first fit, every block aligned to a
// cache line so that two owners never share one. Not in shared memory: only the node allocates.
class ArenaAllocator {
public:
  static constexpr std::size_t kAlign = 64;
  explicit ArenaAllocator(std::size_t bytes);
  std::optional<std::uint64_t> allocate(std::size_t bytes);
  void release(std::uint64_t offset);
  std::size_t in_use() const { return in_use_; }

private:
  std::map<std::uint64_t, std::size_t> free_; // offset -> bytes, adjacent blocks merged
  std::map<std::uint64_t, std::size_t> used_;
  std::size_t in_use_ = 0;
};

// What a process learns from kArenaVariable.
struct ArenaGrant {
  int fd = kArenaFd;
  std::uint64_t page = 0; // its own page: the doorbells of its receive threads
  std::uint64_t page_bytes = 0;
  std::string to_string() const;
  static std::optional<ArenaGrant> parse(const std::string &text);
};

} // namespace rsca::shm
