// A topic's ring in the host's arena: how a connection between two processes of one host
// carries its samples without DDS. One ring per topic; any number of writers (serialized by a
// robust process-shared lock) and up to kMaxRingReaders readers, each with its own cursor.
//
// A writer never waits for a reader: a record that does not fit overwrites the oldest, and a
// reader that fell behind loses what was overwritten and counts it. The records a ring still
// holds are the topic's history: a transient-local reader starts among them. Within that bound
// delivery is reliable and in order; a reader of history depth n takes only the newest n records at
// each take (KEEP_LAST). Records are copied out by the reader; one that a writer overwrote while it
// was read is found (the ring's `oldest` passed it: a sequence lock) and dropped, never delivered.
//
// The parties, each with what it may do (as iceoryx splits a port): the node makes the ring and
// owns its bookkeeping (RingOwner: slots, writer counts); a writer (RingWriter) and a reader
// (RingReader) in the processes use what the node gave them.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include <pthread.h>
#include <tl/expected.hpp>

#include "shm/arena.hpp"
#include "shm/doorbell.hpp"

namespace rsca::shm {

inline constexpr std::uint32_t kMaxRingReaders = 128;

// Who wrote a record: a process of this host, or the node relaying what came from other hosts
// (node/topic_bridge.hpp). The node's own reader that carries a ring's records to other hosts
// skips what it relayed in, so that a topic with ends on several hosts never echoes.
enum class Origin : std::uint32_t { Host = 0, Relayed = 1 };

// Whether a reader slot or a writer counts as a peer of the ring's other ends (their matched
// counts): the node's relays do not; the peers they stand for are counted as they match on DDS.
enum class Count : std::uint8_t { Peer, Relay };

struct RingLimits {
  std::uint32_t data_bytes = 256 * 1024; // a power of two; a record takes at most half
  std::uint32_t records = 1024;          // a power of two: the most a reader can fall behind
};

// Why `limits` cannot make a ring (not powers of two, or outside 4 KiB..256 MiB of data and
// 16..1 Mi records), or nothing when they can.
std::optional<std::string> check(const RingLimits &limits);

namespace detail {

enum SlotState : std::uint32_t { kSlotFree = 0, kSlotClaimed = 1, kSlotActive = 2 };

struct ReaderSlot {
  std::atomic<std::uint32_t> state{kSlotFree};
  std::atomic<std::uint64_t> doorbell{0}; // the offset of its reader's Doorbell
};

struct RecordEntry {
  std::atomic<std::uint64_t> seq{~0ull}; // the record's sequence number
  std::atomic<std::uint64_t> pos{0};     // its first byte, as a position (data_bytes wraps it)
  std::atomic<std::uint32_t> bytes{0};
  std::atomic<std::uint32_t> origin{0}; // Origin
};

struct RingHeader {
  std::uint32_t magic = 0;
  std::uint32_t data_bytes = 0;
  std::uint32_t records = 0;
  pthread_mutex_t write_lock;
  alignas(64) std::atomic<std::uint64_t> next_seq{0}; // published: [.., next_seq)
  std::atomic<std::uint64_t> head{0};                 // the position of the next record
  std::atomic<std::uint64_t> oldest{0};               // the oldest record not overwritten
  std::atomic<std::int32_t> writers{0};
  std::atomic<std::int32_t> readers{0};
  std::atomic<std::uint32_t> writers_lost{0}; // writers whose process ended while connected
  std::atomic<std::uint32_t> slots_used{0};   // no slot at or above this was ever claimed
  // When a writer last wrote or said it is alive (steady clock, ns: one clock for the host).
  std::atomic<std::int64_t> alive_ns{0};
  // The same for the host's own writers only (not what the node relayed in): what the node's
  // relay says on DDS for them.
  std::atomic<std::int64_t> host_alive_ns{0};
  // Writers on other hosts that DDS says are alive (the node's relay counts them): while there
  // is one, a lease that passed since the last record is not lost liveliness.
  std::atomic<std::int32_t> remote_alive{0};
  ReaderSlot slots[kMaxRingReaders];
};

// The parts of a ring, found and checked in an arena.
// Its geometry is copied when it is checked: what another process writes into the header later
// cannot move a reader or writer outside the ring.
struct RingView {
  RingHeader *header = nullptr;
  RecordEntry *entries = nullptr;
  std::byte *data = nullptr;
  std::uint32_t data_bytes = 0;
  std::uint32_t records = 0;
  static tl::expected<RingView, std::string> open(const Arena &arena, std::uint64_t offset);
  RecordEntry &entry(std::uint64_t seq) const { return entries[seq & (records - 1)]; }
};

} // namespace detail

// The bytes a ring of these limits takes in the arena.
std::size_t ring_bytes(const RingLimits &limits);

// The node's side of a ring: it makes the ring, and counts who is connected to it.
class RingOwner {
public:
  // Makes a ring at `offset` (ring_bytes(limits) allocated there).
  static tl::expected<RingOwner, std::string> create(const Arena &arena, std::uint64_t offset,
                                                     const RingLimits &limits);
  // A free reader slot, claimed; none when the ring has kMaxRingReaders readers. A relay's slot
  // is not counted among the readers; release it with the same Count.
  std::optional<std::uint32_t> claim_reader(Count count = Count::Peer);
  void release_reader(std::uint32_t slot, Count count = Count::Peer);
  void add_writer();
  // `lost`: the writer's process ended without disconnecting (its readers see it as lost
  // liveliness).
  void remove_writer(bool lost);
  // Peers on other hosts, as the node's relay learns of them from DDS: matched readers of its
  // writer, matched writers of its reader, their writers alive, and those lost.
  void count_remote_readers(std::int32_t change);
  void count_remote_writers(std::int32_t change);
  void count_remote_alive(std::int32_t change);
  void count_writers_lost(std::uint32_t lost);
  // When a writer of this host was last alive (steady clock, ns); 0: never.
  std::int64_t host_alive_ns() const {
    return view_.header->host_alive_ns.load(std::memory_order_relaxed);
  }

private:
  explicit RingOwner(detail::RingView view) : view_(view) {}
  detail::RingView view_;
};

// A writer's side: where a uses port's connection writes.
class RingWriter {
public:
  static tl::expected<RingWriter, std::string> open(const Arena &arena, std::uint64_t offset,
                                                    Origin origin = Origin::Host);

  // Writes one record of `bytes`, filled by `fill(std::byte *)`, and rings the readers' doorbells.
  // An error when the record cannot fit (more than half the ring).
  template <typename Fill>
  tl::expected<void, std::string> write(std::size_t bytes, Fill &&fill) {
    auto at = reserve(bytes);
    if (!at)
      return tl::unexpected(at.error());
    fill(*at);
    publish();
    return {};
  }
  std::int32_t readers() const { return view_.header->readers.load(std::memory_order_relaxed); }
  // The records the ring keeps: the most a reader can fall behind, and a late joiner's history.
  std::uint32_t records() const { return view_.records; }
  // Says the writer is alive without writing (automatic liveliness: shm/ring.cpp).
  void assert_alive();

private:
  RingWriter(const Arena &arena, detail::RingView view, Origin origin)
      : arena_(&arena), view_(view), origin_(origin) {}
  // Takes the write lock and room for `bytes`; publish() gives both back.
  tl::expected<std::byte *, std::string> reserve(std::size_t bytes);
  void publish();
  void ring_readers() const;

  const Arena *arena_;
  detail::RingView view_;
  Origin origin_ = Origin::Host;
  std::uint64_t seq_ = 0, pos_ = 0, bytes_ = 0; // the record reserved
};

// A reader's side: a provides port's connection, in the slot the node claimed for it.
class RingReader {
public:
  // Activates `slot`, whose writers from now on ring `doorbell` (an offset in the arena). It
  // reads what is written from now on and, with `history` n, the last n records the ring still
  // holds (a transient-local late joiner: DDS replays a writer's last samples to it); `depth` 0
  // keeps all (up to the ring's records). `skip_relayed`: records of Origin::Relayed are passed
  // over (the node's relay to DDS).
  static tl::expected<RingReader, std::string> open(const Arena &arena, std::uint64_t offset,
                                                    std::uint32_t slot, std::uint64_t doorbell,
                                                    std::uint32_t depth, bool skip_relayed = false,
                                                    std::uint32_t history = 0);
  RingReader(RingReader &&other) noexcept;
  RingReader &operator=(RingReader &&) = delete;
  RingReader(const RingReader &) = delete;
  ~RingReader(); // the slot is no longer rung; the node frees it

  // Takes every record that arrived: `decode(const std::byte *, std::size_t) -> bool` copies one
  // out; `deliver()` runs for each decoded record that no writer overwrote meanwhile. Returns
  // how many were delivered.
  template <typename Decode, typename Deliver>
  std::size_t take(Decode &&decode, Deliver &&deliver);

  std::uint64_t dropped() const { return dropped_; }
  std::uint32_t depth() const { return depth_; } // the newest kept at each take; 0: all
  // How many records the ring's writers have published so far.
  std::uint64_t written() const { return view_.header->next_seq.load(std::memory_order_acquire); }
  std::int32_t writers() const { return view_.header->writers.load(std::memory_order_relaxed); }
  std::uint32_t writers_lost() const {
    return view_.header->writers_lost.load(std::memory_order_relaxed);
  }
  // When a writer was last alive (steady clock, ns); 0: never.
  std::int64_t alive_ns() const { return view_.header->alive_ns.load(std::memory_order_relaxed); }
  // Writers on other hosts alive now (their node's relay says so).
  std::int32_t remote_alive() const {
    return view_.header->remote_alive.load(std::memory_order_relaxed);
  }

private:
  RingReader(detail::RingView view, std::uint32_t slot, std::uint32_t depth, bool skip_relayed)
      : view_(view), slot_(slot), depth_(depth), skip_relayed_(skip_relayed) {}
  // Moves the cursor past what is lost (overwritten, or beyond the depth); the newest published.
  std::uint64_t skip_lost();

  detail::RingView view_;
  std::uint32_t slot_ = kMaxRingReaders; // kMaxRingReaders: moved from
  std::uint32_t depth_ = 0;
  bool skip_relayed_ = false;
  std::uint64_t cursor_ = 0;
  std::uint64_t dropped_ = 0;
};

template <typename Decode, typename Deliver>
std::size_t RingReader::take(Decode &&decode, Deliver &&deliver) {
  const std::uint64_t end = skip_lost();
  const std::uint32_t capacity = view_.data_bytes;
  std::size_t delivered = 0;
  for (; cursor_ < end; ++cursor_) {
    auto &entry = view_.entry(cursor_);
    if (entry.seq.load(std::memory_order_acquire) != cursor_) {
      ++dropped_; // its entry was taken by a newer record
      continue;
    }
    if (skip_relayed_ &&
        entry.origin.load(std::memory_order_relaxed) == static_cast<std::uint32_t>(Origin::Relayed))
      continue;
    const std::uint64_t pos = entry.pos.load(std::memory_order_relaxed);
    const std::uint32_t bytes = entry.bytes.load(std::memory_order_relaxed);
    const std::uint64_t at = pos & (capacity - 1);
    const bool decoded = bytes <= capacity - at && decode(view_.data + at, std::size_t{bytes});
    std::atomic_thread_fence(std::memory_order_acquire);
    if (!decoded || view_.header->oldest.load(std::memory_order_relaxed) > cursor_) {
      ++dropped_; // overwritten while it was read
      continue;
    }
    deliver();
    ++delivered;
  }
  return delivered;
}

} // namespace rsca::shm
