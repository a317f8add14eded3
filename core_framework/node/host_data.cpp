#include "node/host_data.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "protocol/codec.hpp"
#include "protocol/component_ops.hpp"

namespace rsca::node {

namespace op = protocol::component;

HostData::HostData(shm::Arena arena) : arena_(std::move(arena)), allocator_(arena_.size()) {}

Expected<std::unique_ptr<HostData>> HostData::create(std::size_t bytes) {
  auto arena = shm::Arena::create(bytes);
  if (!arena)
    return tl::unexpected(arena.error());
  return std::unique_ptr<HostData>(new HostData(std::move(*arena)));
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
  pages_[pid] = page;
}

void HostData::release_page(std::uint64_t page) {
  std::lock_guard lock(mutex_);
  allocator_.release(page);
}

tl::expected<HostData::Ring *, std::string> HostData::ring_of_locked(const std::string &topic) {
  if (auto it = rings_.find(topic); it != rings_.end())
    return &it->second;
  const shm::RingLimits limits;
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

tl::expected<nlohmann::json, std::string> HostData::connect(pid_t pid, const std::string &target,
                                                            const nlohmann::json &request) {
  auto r = protocol::decode<op::ConnectRequest>(request);
  if (!r || !r->shared_memory.value_or(false))
    return request; // not ours to change: the process answers what is wrong with it
  if (!r->topic || r->topic->empty())
    return tl::unexpected(std::string("a same-host connection needs its topic"));
  const bool writer = r->direction == "uses";
  std::lock_guard lock(mutex_);
  // A connection made again replaces the one of that id: its end goes first.
  if (auto old = ends_.find({pid, target, r->port, r->connection}); old != ends_.end())
    release_end_locked(old, /*lost=*/false);
  auto ring = ring_of_locked(*r->topic);
  if (!ring)
    return tl::unexpected(ring.error());
  End end{*r->topic, writer, 0};
  if (writer) {
    (*ring)->owner.add_writer();
  } else {
    auto slot = (*ring)->owner.claim_reader();
    if (!slot)
      return tl::unexpected(fmt::format("topic {} has {} same-host readers, the most a ring has",
                                        *r->topic, shm::kMaxRingReaders));
    end.slot = *slot;
  }
  ++(*ring)->ends;
  ends_[{pid, target, r->port, r->connection}] = end;
  nlohmann::json relayed = request;
  relayed["ring"] = protocol::encode_message(op::Ring{(*ring)->offset, end.slot});
  return relayed;
}

void HostData::release_end_locked(std::map<EndKey, End>::iterator end, bool lost) {
  auto ring = rings_.find(end->second.topic);
  if (ring != rings_.end()) {
    if (end->second.writer)
      ring->second.owner.remove_writer(lost);
    else
      ring->second.owner.release_reader(end->second.slot);
    if (--ring->second.ends == 0) {
      allocator_.release(ring->second.offset);
      spdlog::debug("host data: the ring of topic {} is freed", ring->first);
      rings_.erase(ring);
    }
  }
  ends_.erase(end);
}

void HostData::disconnect(pid_t pid, const std::string &target, const std::string &port,
                          const std::string &connection) {
  std::lock_guard lock(mutex_);
  if (auto end = ends_.find({pid, target, port, connection}); end != ends_.end())
    release_end_locked(end, /*lost=*/false);
}

void HostData::forget(pid_t pid) {
  std::lock_guard lock(mutex_);
  for (auto it = ends_.lower_bound({pid, "", "", ""});
       it != ends_.end() && std::get<0>(it->first) == pid;)
    release_end_locked(it++, /*lost=*/true);
  if (auto page = pages_.find(pid); page != pages_.end()) {
    allocator_.release(page->second);
    pages_.erase(page);
  }
}

HostData::Counts HostData::counts() const {
  std::lock_guard lock(mutex_);
  return {rings_.size(), ends_.size(), pages_.size(), allocator_.in_use()};
}

} // namespace rsca::node
