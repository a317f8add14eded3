#include "shm/arena.hpp"

#include <cerrno>
#include <cstring>
#include <utility>

#include <fmt/format.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

namespace rsca::shm {

namespace {

tl::unexpected<Error> arena_error(const std::string &what) {
  return make_error({"shm", 0, 0}, "arena", fmt::format("{}: {}", what, std::strerror(errno)));
}

std::size_t round_up(std::size_t bytes, std::size_t to) {
  return (bytes + to - 1) / to * to;
}

} // namespace

Expected<Arena> Arena::create(std::size_t bytes) {
  process::Fd fd(::memfd_create("rsca-host-arena", MFD_CLOEXEC));
  if (!fd)
    return arena_error("memfd_create");
  if (::ftruncate(fd.get(), static_cast<off_t>(bytes)) != 0)
    return arena_error(fmt::format("sizing the arena to {} bytes", bytes));
  return map(std::move(fd));
}

Expected<Arena> Arena::map(process::Fd fd) {
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0)
    return arena_error("fstat of the arena");
  const auto size = static_cast<std::size_t>(st.st_size);
  if (size == 0)
    return make_error({"shm", 0, 0}, "arena", "the arena is empty");
  void *base = ::mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd.get(), 0);
  if (base == MAP_FAILED)
    return arena_error(fmt::format("mapping the arena of {} bytes", size));
  return Arena(std::move(fd), static_cast<std::byte *>(base), size);
}

Arena::Arena(Arena &&other) noexcept
    : fd_(std::move(other.fd_)), base_(std::exchange(other.base_, nullptr)),
      size_(std::exchange(other.size_, 0)) {}

Arena &Arena::operator=(Arena &&other) noexcept {
  if (this == &other)
    return *this;
  if (base_ != nullptr)
    ::munmap(base_, size_);
  fd_ = std::move(other.fd_);
  base_ = std::exchange(other.base_, nullptr);
  size_ = std::exchange(other.size_, 0);
  return *this;
}

Arena::~Arena() {
  if (base_ != nullptr)
    ::munmap(base_, size_);
}

std::byte *Arena::at(std::uint64_t offset, std::size_t bytes) const {
  if (base_ == nullptr || offset > size_ || bytes > size_ - offset)
    return nullptr;
  return base_ + offset;
}

// The first line is never given out: offset 0 means "none" where an offset is stored in the
// arena (a released reader slot's doorbell).
ArenaAllocator::ArenaAllocator(std::size_t bytes) {
  if (bytes >= 2 * kAlign)
    free_[kAlign] = bytes / kAlign * kAlign - kAlign;
}

std::optional<std::uint64_t> ArenaAllocator::allocate(std::size_t bytes) {
  const std::size_t need = round_up(std::max<std::size_t>(bytes, 1), kAlign);
  for (auto it = free_.begin(); it != free_.end(); ++it) {
    if (it->second < need)
      continue;
    const auto [offset, size] = *it;
    free_.erase(it);
    if (size > need)
      free_[offset + need] = size - need;
    used_[offset] = need;
    in_use_ += need;
    return offset;
  }
  return std::nullopt;
}

void ArenaAllocator::release(std::uint64_t offset) {
  auto used = used_.find(offset);
  if (used == used_.end())
    return;
  std::size_t size = used->second;
  in_use_ -= size;
  used_.erase(used);
  auto next = free_.find(offset + size);
  if (next != free_.end()) {
    size += next->second;
    free_.erase(next);
  }
  auto after = free_.lower_bound(offset);
  if (after != free_.begin()) {
    auto before = std::prev(after);
    if (before->first + before->second == offset) {
      before->second += size;
      return;
    }
  }
  free_[offset] = size;
}

std::string ArenaGrant::to_string() const {
  return fmt::format("{}:{}:{}", fd, page, page_bytes);
}

std::optional<ArenaGrant> ArenaGrant::parse(const std::string &text) {
  ArenaGrant grant;
  unsigned long long page = 0, bytes = 0;
  int used = 0;
  if (std::sscanf(text.c_str(), "%d:%llu:%llu%n", &grant.fd, &page, &bytes, &used) != 3 ||
      static_cast<std::size_t>(used) != text.size() || grant.fd < 0)
    return std::nullopt;
  grant.page = page;
  grant.page_bytes = bytes;
  return grant;
}

} // namespace rsca::shm
