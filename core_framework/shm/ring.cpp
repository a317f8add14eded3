#include "shm/ring.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <new>
#include <utility>

#include <fmt/format.h>

namespace rsca::shm {

using detail::RecordEntry;
using detail::RingHeader;
using detail::RingView;

namespace {

constexpr std::uint32_t kRingMagic = 0x72736372; // "rscr"

bool power_of_two(std::uint32_t n) {
  return n != 0 && (n & (n - 1)) == 0;
}

std::size_t entries_offset() {
  return (sizeof(RingHeader) + alignof(RecordEntry) - 1) / alignof(RecordEntry) *
         alignof(RecordEntry);
}

std::size_t data_offset(std::uint32_t records) {
  return (entries_offset() + records * sizeof(RecordEntry) + 63) / 64 * 64;
}

// A writer that died holding the lock left at most a record reserved and not published: the
// ring is consistent, and the lock is taken over.
void lock(pthread_mutex_t &mutex) {
  if (pthread_mutex_lock(&mutex) == EOWNERDEAD)
    pthread_mutex_consistent(&mutex);
}

std::int64_t steady_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

} // namespace

std::optional<std::string> check(const RingLimits &limits) {
  if (!power_of_two(limits.data_bytes) || !power_of_two(limits.records))
    return "a ring's bytes and records are powers of two";
  if (limits.data_bytes < (4U << 10U) || limits.data_bytes > (256U << 20U))
    return fmt::format("a ring holds 4 KiB to 256 MiB of data, not {} bytes", limits.data_bytes);
  if (limits.records < 16 || limits.records > (1U << 20U))
    return fmt::format("a ring holds 16 to 1048576 records, not {}", limits.records);
  return std::nullopt;
}

std::size_t ring_bytes(const RingLimits &limits) {
  return data_offset(limits.records) + limits.data_bytes;
}

tl::expected<RingView, std::string> RingView::open(const Arena &arena, std::uint64_t offset) {
  auto *header = arena.object<RingHeader>(offset);
  if (header == nullptr)
    return tl::unexpected(fmt::format("no ring fits at offset {} of the host's arena", offset));
  if (header->magic != kRingMagic || !power_of_two(header->data_bytes) ||
      !power_of_two(header->records))
    return tl::unexpected(fmt::format("no ring at offset {} of the host's arena", offset));
  std::byte *whole = arena.at(offset, data_offset(header->records) + header->data_bytes);
  if (whole == nullptr)
    return tl::unexpected(fmt::format("the ring at offset {} overruns the host's arena", offset));
  return RingView{header, reinterpret_cast<RecordEntry *>(whole + entries_offset()),
                  whole + data_offset(header->records), header->data_bytes, header->records};
}

tl::expected<RingOwner, std::string> RingOwner::create(const Arena &arena, std::uint64_t offset,
                                                       const RingLimits &limits) {
  if (auto why = check(limits))
    return tl::unexpected(*why);
  std::byte *at = arena.at(offset, ring_bytes(limits));
  if (at == nullptr || offset % alignof(RingHeader) != 0)
    return tl::unexpected(fmt::format("no ring of {} bytes fits at offset {} of the arena",
                                      ring_bytes(limits), offset));
  auto *header = new (at) RingHeader();
  header->data_bytes = limits.data_bytes;
  header->records = limits.records;
  pthread_mutexattr_t attributes;
  pthread_mutexattr_init(&attributes);
  pthread_mutexattr_setpshared(&attributes, PTHREAD_PROCESS_SHARED);
  pthread_mutexattr_setrobust(&attributes, PTHREAD_MUTEX_ROBUST);
  pthread_mutex_init(&header->write_lock, &attributes);
  pthread_mutexattr_destroy(&attributes);
  auto *entries = reinterpret_cast<RecordEntry *>(at + entries_offset());
  for (std::uint32_t i = 0; i < limits.records; ++i)
    new (entries + i) RecordEntry();
  std::atomic_thread_fence(std::memory_order_release);
  header->magic = kRingMagic;
  auto view = RingView::open(arena, offset);
  if (!view)
    return tl::unexpected(view.error());
  return RingOwner(*view);
}

std::optional<std::uint32_t> RingOwner::claim_reader(Count count) {
  auto &h = *view_.header;
  for (std::uint32_t slot = 0; slot < kMaxRingReaders; ++slot) {
    std::uint32_t expected = detail::kSlotFree;
    if (!h.slots[slot].state.compare_exchange_strong(expected, detail::kSlotClaimed))
      continue;
    std::uint32_t used = h.slots_used.load();
    while (used < slot + 1 && !h.slots_used.compare_exchange_weak(used, slot + 1)) {
    }
    if (count == Count::Peer)
      h.readers.fetch_add(1);
    return slot;
  }
  return std::nullopt;
}

void RingOwner::release_reader(std::uint32_t slot, Count count) {
  if (slot >= kMaxRingReaders)
    return;
  auto &s = view_.header->slots[slot];
  if (s.state.exchange(detail::kSlotFree) != detail::kSlotFree && count == Count::Peer)
    view_.header->readers.fetch_sub(1);
  s.doorbell.store(0);
}

void RingOwner::add_writer() {
  view_.header->writers.fetch_add(1);
}

void RingOwner::remove_writer(bool lost) {
  view_.header->writers.fetch_sub(1);
  if (lost)
    view_.header->writers_lost.fetch_add(1);
}

void RingOwner::count_remote_readers(std::int32_t change) {
  view_.header->readers.fetch_add(change);
}

void RingOwner::count_remote_writers(std::int32_t change) {
  view_.header->writers.fetch_add(change);
}

void RingOwner::count_remote_alive(std::int32_t change) {
  view_.header->remote_alive.fetch_add(change);
}

void RingOwner::count_writers_lost(std::uint32_t lost) {
  view_.header->writers_lost.fetch_add(lost);
}

tl::expected<RingWriter, std::string> RingWriter::open(const Arena &arena, std::uint64_t offset,
                                                       Origin origin) {
  auto view = RingView::open(arena, offset);
  if (!view)
    return tl::unexpected(view.error());
  return RingWriter(arena, *view, origin);
}

tl::expected<std::byte *, std::string> RingWriter::reserve(std::size_t bytes) {
  auto &h = *view_.header;
  const std::uint64_t capacity = view_.data_bytes;
  if (bytes > capacity / 2)
    return tl::unexpected(
        fmt::format("a sample of {} bytes does not fit a ring of {} bytes", bytes, capacity));
  lock(h.write_lock);
  std::uint64_t pos = h.head.load(std::memory_order_relaxed);
  if ((pos & (capacity - 1)) + bytes > capacity) // a record never wraps: it starts over
    pos += capacity - (pos & (capacity - 1));
  const std::uint64_t seq = h.next_seq.load(std::memory_order_relaxed);
  // The records this one overwrites (they start in the last `capacity` bytes before its end),
  // and the one whose index entry it takes, are lost: readers learn it before a byte changes.
  std::uint64_t oldest = h.oldest.load(std::memory_order_relaxed);
  while (oldest < seq &&
         (view_.entry(oldest).pos.load(std::memory_order_relaxed) + capacity < pos + bytes ||
          seq - oldest >= view_.records))
    ++oldest;
  h.oldest.store(oldest, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
  seq_ = seq;
  pos_ = pos;
  bytes_ = bytes;
  return view_.data + (pos & (capacity - 1));
}

void RingWriter::assert_alive() {
  const std::int64_t now = steady_now_ns();
  view_.header->alive_ns.store(now, std::memory_order_relaxed);
  if (origin_ == Origin::Host)
    view_.header->host_alive_ns.store(now, std::memory_order_relaxed);
}

void RingWriter::publish() {
  auto &h = *view_.header;
  auto &entry = view_.entry(seq_);
  entry.pos.store(pos_, std::memory_order_relaxed);
  entry.bytes.store(static_cast<std::uint32_t>(bytes_), std::memory_order_relaxed);
  entry.origin.store(static_cast<std::uint32_t>(origin_), std::memory_order_relaxed);
  entry.seq.store(seq_, std::memory_order_release);
  h.head.store(pos_ + bytes_, std::memory_order_relaxed);
  h.next_seq.store(seq_ + 1, std::memory_order_release);
  pthread_mutex_unlock(&h.write_lock);
  // Against a reader that becomes active meanwhile (RingReader::open): either it sees this
  // record's sequence number, or this writer sees it active and rings it.
  std::atomic_thread_fence(std::memory_order_seq_cst);
  assert_alive(); // a write is a sign of life, as in DDS
  ring_readers();
}

void RingWriter::ring_readers() const {
  const auto &h = *view_.header;
  const std::uint32_t used = std::min(h.slots_used.load(), kMaxRingReaders);
  for (std::uint32_t i = 0; i < used; ++i) {
    const auto &slot = h.slots[i];
    if (slot.state.load(std::memory_order_acquire) != detail::kSlotActive)
      continue;
    const std::uint64_t at = slot.doorbell.load(std::memory_order_relaxed);
    if (at == 0) // released meanwhile (the arena's first bytes are never given out)
      continue;
    if (auto *bell = arena_->object<Doorbell>(at))
      ring(*bell, kWakeNearData, /*shared=*/true);
  }
}

tl::expected<RingReader, std::string> RingReader::open(const Arena &arena, std::uint64_t offset,
                                                       std::uint32_t slot, std::uint64_t doorbell,
                                                       std::uint32_t depth, bool skip_relayed,
                                                       std::uint32_t history) {
  auto view = RingView::open(arena, offset);
  if (!view)
    return tl::unexpected(view.error());
  if (slot >= kMaxRingReaders)
    return tl::unexpected(fmt::format("reader slot {} is not a ring's", slot));
  if (arena.object<Doorbell>(doorbell) == nullptr)
    return tl::unexpected(fmt::format("no doorbell at offset {} of the arena", doorbell));
  auto &s = view->header->slots[slot];
  if (s.state.load() != detail::kSlotClaimed)
    return tl::unexpected(fmt::format("reader slot {} was not claimed for this reader", slot));
  RingReader reader(*view, slot, depth, skip_relayed);
  s.doorbell.store(doorbell, std::memory_order_relaxed);
  s.state.store(detail::kSlotActive, std::memory_order_seq_cst);
  // After the slot is active (publish() says why the order matters): what is published from
  // here on either is read from this cursor or rings the doorbell.
  // History starts at the oldest record the ring still holds, at most `history` back.
  const std::uint64_t next = view->header->next_seq.load(std::memory_order_seq_cst);
  const std::uint64_t oldest = view->header->oldest.load(std::memory_order_acquire);
  reader.cursor_ = std::max(oldest, next - std::min<std::uint64_t>(next, history));
  return reader;
}

RingReader::RingReader(RingReader &&other) noexcept
    : view_(other.view_), slot_(std::exchange(other.slot_, kMaxRingReaders)), depth_(other.depth_),
      skip_relayed_(other.skip_relayed_), cursor_(other.cursor_), dropped_(other.dropped_) {}

RingReader::~RingReader() {
  if (slot_ >= kMaxRingReaders)
    return;
  std::uint32_t active = detail::kSlotActive;
  view_.header->slots[slot_].state.compare_exchange_strong(active, detail::kSlotClaimed);
}

std::uint64_t RingReader::skip_lost() {
  const auto &h = *view_.header;
  const std::uint64_t end = h.next_seq.load(std::memory_order_acquire);
  if (depth_ != 0 && end - cursor_ > depth_) {
    dropped_ += end - depth_ - cursor_;
    cursor_ = end - depth_;
  }
  const std::uint64_t oldest = h.oldest.load(std::memory_order_acquire);
  if (cursor_ < oldest) {
    dropped_ += oldest - cursor_;
    cursor_ = oldest;
  }
  return end;
}

} // namespace rsca::shm
