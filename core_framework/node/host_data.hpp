// The node's shared memory for its host's data: the part of the host agent that iceoryx gives to
// RouDi. The node makes the arena (shm/arena.hpp) its processes inherit, gives each a page for
// the doorbells of its receive threads, and makes a ring (shm/ring.hpp) per same-host topic at
// the first `component.connect` that asks for one; it counts each end, and frees the ring when
// its last end goes: disconnected, failed to connect, or its process ended. A writer whose
// process ended without disconnecting is counted as lost: its readers see lost liveliness.
//
// Only the node allocates and counts; the processes use what it gave them (the offsets in the
// relayed request). It is called from the relay (node/process_links.cpp), hence its own lock.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <tuple>

#include <sys/types.h>
#include <tl/expected.hpp>

#include "common/diagnostic.hpp"
#include "node/topic_bridge.hpp"
#include "node/topic_tap.hpp"
#include "protocol/component_ops.hpp"
#include "shm/arena.hpp"
#include "shm/ring.hpp"

namespace rsca::node {

class HostData {
public:
  // 1 GiB of address space; memory is taken only as rings and pages are used.
  static constexpr std::size_t kArenaBytes = std::size_t{1} << 30;
  // A process's doorbells, one per component receive thread: 4096 (a component host of
  // thousands of components). Memory is taken only as they are used.
  static constexpr std::size_t kPageBytes = 256 * 1024;

  // Each same-host ring is made with `rings` (shm::check says which limits can be).
  static Expected<std::unique_ptr<HostData>> create(shm::RingLimits rings = {},
                                                    std::size_t bytes = kArenaBytes);

  int arena_fd() const { return arena_.fd(); }

  // Relays rings with ends on other hosts (a connect with `relay`) through the relay `make`
  // returns for this arena and a doorbell in it (node/topic_bridge.hpp). Without one, such a
  // connect is refused.
  using MakeRelay = std::function<Expected<std::unique_ptr<TopicRelay>>(const shm::Arena &arena,
                                                                        std::uint64_t doorbell)>;
  Expected<void> start_relay(const MakeRelay &make);
  // Taps rings for viewers (node.tap) through the taps `make` returns for this arena and a
  // doorbell of their own in it (node/topic_tap.hpp). Without them, a tap is refused.
  using MakeTaps = std::function<Expected<std::unique_ptr<TopicTaps>>(const shm::Arena &arena,
                                                                      std::uint64_t doorbell)>;
  Expected<void> start_taps(const MakeTaps &make);
  // A viewer's tap of `route.topic`'s ring, opened or renewed: its DDS topic. An error when this
  // host has no ring of that topic.
  tl::expected<std::string, std::string> tap(TapRoute route);
  // A page for a process about to start, and the value of shm::kArenaVariable that tells it
  // (the arena at shm::kArenaFd); adopt() binds it to the process once it runs.
  std::optional<std::pair<std::uint64_t, std::string>> reserve_page();
  void adopt(pid_t pid, std::uint64_t page);
  void release_page(std::uint64_t page);

  // A relayed component.connect to `target` (served by process `pid`) that asks for shared
  // memory: the topic's ring, made or found, with a new end counted (pending until connected()),
  // for the request to carry. An error says why the node cannot.
  tl::expected<protocol::component::Ring, std::string>
  connect(pid_t pid, const std::string &target, const protocol::component::ConnectRequest &r);
  // The process answered that connect. Made: the end it replaced (a connection made again under
  // its id) goes, now that the process has let go of it, and the new one is kept. Not made: the
  // new one goes, and the process keeps the one it had.
  void connected(pid_t pid, const std::string &target, const std::string &port,
                 const std::string &connection, bool made);
  // The end goes: disconnected. Nothing if it has none.
  void disconnect(pid_t pid, const std::string &target, const std::string &port,
                  const std::string &connection);
  // The process ended: its page and its ends go.
  void forget(pid_t pid);

  struct Counts {
    std::size_t rings = 0;
    std::size_t ends = 0;
    std::size_t pages = 0;
    std::size_t bytes_in_use = 0;
    std::size_t relays = 0; // as the relay counts them
  };
  Counts counts() const;

private:
  struct Ring {
    std::uint64_t offset = 0;
    shm::RingOwner owner;
    std::size_t ends = 0;
    std::size_t relayed_writers = 0; // ends whose records the relay carries out
    std::size_t relayed_readers = 0; // ends the relay brings other hosts' samples to
  };
  struct End {
    std::string topic;
    bool writer = false;
    std::uint32_t slot = 0;
    bool relayed = false;
  };
  // (pid, target, port, connection)
  using EndKey = std::tuple<pid_t, std::string, std::string, std::string>;

  HostData(shm::Arena arena, shm::RingLimits rings);
  // What `make` makes with a doorbell of its own in the arena, and the doorbell's offset.
  template <typename Make>
  auto with_doorbell_locked(const Make &make, const char *what);
  tl::expected<Ring *, std::string> ring_of_locked(const std::string &topic);
  void release_locked(const End &end, bool lost);
  void free_ring_locked(const std::string &topic);
  // Counts a relayed end of `ring`, opening the relay its direction needs with the first.
  tl::expected<void, std::string> relay_locked(Ring &ring, const End &end,
                                               const protocol::component::ConnectRequest &r);
  // Takes the end of `key` out of `ends` and releases it; nothing if there is none.
  void release_locked(std::map<EndKey, End> &ends, const EndKey &key, bool lost);

  shm::Arena arena_;
  const shm::RingLimits ring_limits_;
  mutable std::mutex mutex_; // guards what follows
  shm::ArenaAllocator allocator_;
  std::map<std::string, Ring> rings_; // by topic
  std::map<EndKey, End> ends_;        // connected
  std::map<EndKey, End> pending_;     // relayed, not answered yet
  std::map<pid_t, std::uint64_t> pages_;
  std::uint64_t relay_doorbell_ = 0;
  // Declared last: destroyed first, while the arena and its rings are still there.
  std::unique_ptr<TopicTaps> taps_;
  std::unique_ptr<TopicRelay> relay_;
};

} // namespace rsca::node
