#include "node/host_data.hpp"

#include <cerrno>
#include <new>

#include <fmt/format.h>
#include <signal.h>
#include <spdlog/spdlog.h>

namespace rsca::node {

namespace component_op = protocol::component;

HostData::HostData(shm::Arena arena, shm::RingLimits rings)
    : arena_(std::move(arena)), ring_limits_(rings), allocator_(arena_.size()) {}

Expected<std::unique_ptr<HostData>> HostData::create(shm::RingLimits rings, std::size_t bytes) {
  if (auto why = shm::check(rings))
    return make_error({"node", 0, 0}, "ring", *why);
  auto arena = shm::Arena::create(bytes);
  if (!arena)
    return tl::unexpected(arena.error());
  return std::unique_ptr<HostData>(new HostData(std::move(*arena), rings));
}

// The relay's thread and the taps' sleep each on a doorbell of their own: it goes again when
// `make` fails.
template <typename Make>
auto HostData::with_doorbell_locked(const Make &make, const char *what) {
  using Made = std::decay_t<decltype(*make(arena_, std::uint64_t{0}))>;
  using Result = Expected<std::pair<Made, std::uint64_t>>;
  auto doorbell = allocator_.allocate(sizeof(shm::Doorbell));
  if (!doorbell)
    return Result(make_error({"node", 0, 0}, what, "the host's arena has no room for a doorbell"));
  new (arena_.at(*doorbell, sizeof(shm::Doorbell))) shm::Doorbell();
  auto made = make(arena_, *doorbell);
  if (!made) {
    allocator_.release(*doorbell);
    return Result(tl::unexpected(made.error()));
  }
  return Result(std::pair{std::move(*made), *doorbell});
}

Expected<void> HostData::start_relay(const MakeRelay &make) {
  std::lock_guard lock(mutex_);
  auto relay = with_doorbell_locked(make, "relay");
  if (!relay)
    return tl::unexpected(relay.error());
  std::tie(relay_, relay_doorbell_) = std::move(*relay);
  return {};
}

Expected<void> HostData::start_taps(const MakeTaps &make) {
  std::lock_guard lock(mutex_);
  auto taps = with_doorbell_locked(make, "tap");
  if (!taps)
    return tl::unexpected(taps.error());
  taps_ = std::move(taps->first);
  return {};
}

tl::expected<std::string, std::string> HostData::tap(TapRoute route) {
  std::lock_guard lock(mutex_);
  if (!taps_)
    return tl::unexpected(
        std::string("this node has no taps (no shared memory for its host's data)"));
  auto ring = rings_.find(route.topic);
  if (ring == rings_.end())
    return tl::unexpected(
        fmt::format("no same-host ring of topic {} on this node (its writer is not here, or the "
                    "connection is gone)",
                    route.topic));
  route.ring = ring->second.offset;
  return taps_->open(route, ring->second.owner);
}

std::optional<std::pair<std::uint64_t, std::string>> HostData::reserve_page() {
  std::lock_guard lock(mutex_);
  auto page = allocator_.allocate(kPageBytes);
  if (!page)
    return std::nullopt;
  const shm::ArenaGrant grant{shm::kArenaFd, *page, kPageBytes};
  return std::pair{*page, grant.to_string()};
}

void HostData::adopt(pid_t pid, std::uint64_t page) {
  std::lock_guard lock(mutex_);
  // A process that died before it was adopted has been forgotten already: its page goes now.
  // (Its zombie still answers kill 0 until reaped; a reaped one does not.)
  if (::kill(pid, 0) != 0 && errno == ESRCH) {
    allocator_.release(page);
    return;
  }
  if (auto old = pages_.find(pid); old != pages_.end()) // a pid used again
    allocator_.release(old->second);
  pages_[pid] = page;
}

void HostData::release_page(std::uint64_t page) {
  std::lock_guard lock(mutex_);
  allocator_.release(page);
}

tl::expected<HostData::Ring *, std::string> HostData::ring_of_locked(const std::string &topic) {
  if (auto it = rings_.find(topic); it != rings_.end())
    return &it->second;
  const shm::RingLimits &limits = ring_limits_;
  auto offset = allocator_.allocate(shm::ring_bytes(limits));
  if (!offset)
    return tl::unexpected(
        fmt::format("the host's arena is full ({} bytes in use)", allocator_.in_use()));
  auto owner = shm::RingOwner::create(arena_, *offset, limits);
  if (!owner) {
    allocator_.release(*offset);
    return tl::unexpected(owner.error());
  }
  spdlog::debug("host data: a ring for topic {} at offset {}", topic, *offset);
  return &rings_.emplace(topic, Ring{*offset, *owner, 0}).first->second;
}

tl::expected<component_op::Ring, std::string>
HostData::connect(pid_t pid, const std::string &target, const component_op::ConnectRequest &r) {
  if (!r.topic || r.topic->empty())
    return tl::unexpected(std::string("a same-host connection needs its topic"));
  const bool writer = r.direction == "uses";
  const EndKey key{pid, target, r.port, r.connection};
  std::lock_guard lock(mutex_);
  release_locked(pending_, key, /*lost=*/false); // an earlier connect of it never answered
  auto ring = ring_of_locked(*r.topic);
  if (!ring)
    return tl::unexpected(ring.error());
  End end{*r.topic, writer, 0};
  if (writer) {
    (*ring)->owner.add_writer();
  } else {
    auto slot = (*ring)->owner.claim_reader();
    if (!slot) {
      if ((*ring)->ends == 0)
        free_ring_locked(*r.topic);
      return tl::unexpected(fmt::format("topic {} has {} same-host readers, the most a ring has",
                                        *r.topic, shm::kMaxRingReaders));
    }
    end.slot = *slot;
  }
  ++(*ring)->ends;
  if (r.relay.value_or(false)) {
    if (auto relayed = relay_locked(**ring, end, r); !relayed) {
      release_locked(end, /*lost=*/false);
      return tl::unexpected(relayed.error());
    }
    end.relayed = true;
  }
  pending_[key] = end;
  return component_op::Ring{(*ring)->offset, end.slot};
}

tl::expected<void, std::string> HostData::relay_locked(Ring &ring, const End &end,
                                                       const component_op::ConnectRequest &r) {
  if (!relay_)
    return tl::unexpected(std::string("this node relays no data to other hosts"));
  auto &relayed = end.writer ? ring.relayed_writers : ring.relayed_readers;
  if (relayed == 0) {
    const RelayRoute route{end.topic, ring.offset, end.writer, r.repid,
                           r.qos.value_or(nlohmann::json::object())};
    if (auto opened = relay_->open(route, ring.owner); !opened)
      return opened;
  }
  ++relayed;
  return {};
}

void HostData::connected(pid_t pid, const std::string &target, const std::string &port,
                         const std::string &connection, bool made) {
  const EndKey key{pid, target, port, connection};
  std::lock_guard lock(mutex_);
  auto pending = pending_.find(key);
  if (!made) {
    release_locked(pending_, key, /*lost=*/false);
    return;
  }
  release_locked(ends_, key, /*lost=*/false); // the one it replaced, if any
  if (pending == pending_.end())
    return;
  ends_[key] = pending->second;
  pending_.erase(pending);
}

void HostData::free_ring_locked(const std::string &topic) {
  auto ring = rings_.find(topic);
  if (ring == rings_.end())
    return;
  if (taps_) // it reads the ring: it goes first
    taps_->close(topic);
  allocator_.release(ring->second.offset);
  spdlog::debug("host data: the ring of topic {} is freed", topic);
  rings_.erase(ring);
}

void HostData::release_locked(const End &end, bool lost) {
  auto ring = rings_.find(end.topic);
  if (ring == rings_.end())
    return;
  if (end.relayed && relay_) {
    auto &relayed = end.writer ? ring->second.relayed_writers : ring->second.relayed_readers;
    if (relayed > 0 && --relayed == 0)
      relay_->close(end.topic, end.writer);
  }
  if (end.writer)
    ring->second.owner.remove_writer(lost);
  else
    ring->second.owner.release_reader(end.slot);
  if (--ring->second.ends == 0)
    free_ring_locked(end.topic);
}

void HostData::release_locked(std::map<EndKey, End> &ends, const EndKey &key, bool lost) {
  auto end = ends.find(key);
  if (end == ends.end())
    return;
  release_locked(end->second, lost);
  ends.erase(end);
}

void HostData::disconnect(pid_t pid, const std::string &target, const std::string &port,
                          const std::string &connection) {
  std::lock_guard lock(mutex_);
  release_locked(ends_, {pid, target, port, connection}, /*lost=*/false);
}

void HostData::forget(pid_t pid) {
  std::lock_guard lock(mutex_);
  for (auto *ends : {&ends_, &pending_})
    for (auto it = ends->lower_bound({pid, "", "", ""});
         it != ends->end() && std::get<0>(it->first) == pid;) {
      release_locked(it->second, /*lost=*/true);
      it = ends->erase(it);
    }
  if (auto page = pages_.find(pid); page != pages_.end()) {
    allocator_.release(page->second);
    pages_.erase(page);
  }
}

HostData::Counts HostData::counts() const {
  std::lock_guard lock(mutex_);
  return {rings_.size(), ends_.size() + pending_.size(), pages_.size(), allocator_.in_use(),
          relay_ ? relay_->relays() : 0};
}

} // namespace rsca::node
