#include "shm/process_arena.hpp"

#include <cstdlib>
#include <memory>
#include <new>

#include <spdlog/spdlog.h>

namespace rsca::shm {

namespace {

constexpr std::uint64_t kDoorbellSpacing = 64; // one cache line each: no false sharing

std::unique_ptr<ProcessArena> map_inherited() {
  const char *text = std::getenv(kArenaVariable);
  if (text == nullptr || *text == '\0')
    return nullptr;
  const auto grant = ArenaGrant::parse(text);
  if (!grant) {
    spdlog::warn("{}=\"{}\" is not <fd>:<page>:<bytes>: same-host connections go over DDS",
                 kArenaVariable, text);
    return nullptr;
  }
  auto arena = Arena::map(process::Fd(grant->fd));
  if (!arena) {
    spdlog::warn("the host's arena: {}; same-host connections go over DDS",
                 arena.error().to_string());
    return nullptr;
  }
  if (arena->at(grant->page, grant->page_bytes) == nullptr) {
    spdlog::warn("the page the node gave is outside its arena: same-host connections go over DDS");
    return nullptr;
  }
  return std::make_unique<ProcessArena>(std::move(*arena), grant->page, grant->page_bytes);
}

} // namespace

ProcessArena *ProcessArena::inherited() {
  static const std::unique_ptr<ProcessArena> arena = map_inherited();
  return arena.get();
}

ProcessArena::ProcessArena(Arena arena, std::uint64_t page, std::uint64_t page_bytes)
    : arena_(std::move(arena)) {
  for (std::uint64_t at = page + page_bytes; at >= page + kDoorbellSpacing;) {
    at -= kDoorbellSpacing;
    free_.push_back(at); // the lowest offset is taken first
  }
}

Doorbell *ProcessArena::allocate_doorbell() {
  std::lock_guard lock(mutex_);
  if (free_.empty())
    return nullptr;
  const std::uint64_t offset = free_.back();
  free_.pop_back();
  return new (arena_.at(offset, sizeof(Doorbell))) Doorbell();
}

void ProcessArena::release_doorbell(Doorbell *bell) {
  if (bell == nullptr)
    return;
  std::lock_guard lock(mutex_);
  free_.push_back(arena_.offset_of(bell));
}

} // namespace rsca::shm
