#include "node/topic_bridge.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <optional>
#include <vector>

#include <pthread.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/env_duration.hpp"
#include "component/port_types.hpp"
#include "component/record_relay.hpp"
#include "dds/port_qos.hpp"

namespace rsca::node {

namespace {

// The most matched endpoints a relay counts at once (a topic's readers or writers on other
// hosts, each a node or a process of its own).
constexpr std::size_t kMostMatched = 1024;

// How long the relay's thread looks for more of the host's records after it relayed some, before
// it sleeps: RSCA_RELAY_SPIN_US, 0 (never spins) by default. Meant to save the wake of the
// sending node's relay that makes a round trip between hosts 1.46x raw DDS's; in a ping-pong the
// next record comes a round trip later (~70-110 us here), so only a spin longer than that can
// help. Measured on the shared 2-core VM (docs/measurements.md, "The relay thread that spins"),
// 200 us did not lower the p50 and in one series of three quadrupled it, while the two relays
// took ~1 CPU each during the exchange: spinning threads take the CPU from the ones that must
// run next when the host is busy. Off until a quiet host shows it pays.
std::chrono::microseconds relay_spin_time() {
  static const std::chrono::microseconds spin =
      microseconds_from_env("RSCA_RELAY_SPIN_US", std::chrono::microseconds{0});
  return spin;
}

struct ListenerDeleter {
  void operator()(dds_listener_t *l) const { dds_delete_listener(l); }
};
using Listener = std::unique_ptr<dds_listener_t, ListenerDeleter>;

std::int32_t count_except(dds_entity_t entity, bool publications, dds_instance_handle_t own) {
  std::vector<dds_instance_handle_t> handles(kMostMatched);
  const dds_return_t n =
      publications ? dds_get_matched_publications(entity, handles.data(), handles.size())
                   : dds_get_matched_subscriptions(entity, handles.data(), handles.size());
  if (n < 0)
    return 0;
  const auto end = handles.begin() + std::min<dds_return_t>(n, kMostMatched);
  return static_cast<std::int32_t>(std::count_if(
      handles.begin(), end, [own](dds_instance_handle_t h) { return own == 0 || h != own; }));
}

} // namespace

struct TopicBridge::Relay {
  explicit Relay(shm::RingOwner ring_owner, shm::Doorbell *doorbell)
      : owner(ring_owner), bell(doorbell) {}
  ~Relay() { // the DDS entities first: their listeners use what follows
    reader.reset();
    writer.reset();
  }

  // Guards what follows against the bridge's thread, which pumps the relay without the bridge's
  // lock (a DDS write may wait): a closed relay's ring may be freed, and is never touched again.
  std::mutex lock;
  bool closed = false;
  shm::RingOwner owner;
  shm::Doorbell *bell; // the bridge's: rung by the listeners, for the thread to recount
  dds::Entity topic;

  // Out: the host's records to DDS.
  dds::Entity writer;
  std::unique_ptr<component::RecordRelay> out_convert;
  std::optional<shm::RingReader> ring_reader;
  std::uint32_t slot = shm::kMaxRingReaders;
  std::atomic<std::int64_t> lease_ns{0}; // >0: the writer's liveliness is asserted by hand
  std::int64_t alive_seen = 0;           // the ring's alive_ns last asserted

  // In: DDS's samples to the ring.
  dds::Entity reader;
  std::unique_ptr<component::RecordRelay> in_convert;
  std::optional<shm::RingWriter> ring_writer;

  std::atomic<dds_instance_handle_t> own_writer{0}, own_reader{0};
  // Set by the listeners (no waiting there), applied to the ring by the bridge's thread.
  std::atomic<bool> recount{false};
  std::atomic<std::int32_t> alive_now{0}; // the reader's alive writers, its own among them
  std::atomic<std::int32_t> own_alive{0}; // this node's own writer, when alive (not a peer)
  std::atomic<std::uint32_t> lost_pending{0};
  // What the thread counted into the ring: taken back when the relay closes.
  std::int32_t readers_counted = 0, writers_counted = 0, alive_counted = 0;

  bool idle() const { return !writer && !reader; }
  std::size_t pump(); // the records relayed out
  void apply_counts();
  void uncount();
};

namespace {

void on_matched(dds_entity_t, void *arg) {
  auto *relay = static_cast<TopicBridge::Relay *>(arg);
  relay->recount.store(true);
  shm::ring(*relay->bell, shm::kWakeData, /*shared=*/true);
}
void on_publication_matched(dds_entity_t e, const dds_publication_matched_status_t, void *arg) {
  on_matched(e, arg);
}
void on_subscription_matched(dds_entity_t e, const dds_subscription_matched_status_t, void *arg) {
  on_matched(e, arg);
}
void on_liveliness_changed(dds_entity_t e, const dds_liveliness_changed_status_t status,
                           void *arg) {
  auto *relay = static_cast<TopicBridge::Relay *>(arg);
  // The node's own writer of the topic (an event channel with publishers here too) is matched by
  // its own reader: its liveliness is not a peer's.
  const auto own = relay->own_writer.load();
  if (own != 0 && status.last_publication_handle == own)
    relay->own_alive.fetch_add(status.alive_count_change);
  else if (status.not_alive_count_change > 0)
    relay->lost_pending.fetch_add(static_cast<std::uint32_t>(status.not_alive_count_change));
  relay->alive_now.store(static_cast<std::int32_t>(status.alive_count));
  on_matched(e, arg);
}
void on_data_available(dds_entity_t reader, void *arg) {
  auto *relay = static_cast<TopicBridge::Relay *>(arg);
  relay->in_convert->from_dds(reader, relay->own_writer.load(), *relay->ring_writer);
}

} // namespace

std::size_t TopicBridge::Relay::pump() {
  std::size_t relayed = 0;
  if (writer && ring_reader) {
    relayed = out_convert->to_dds(*ring_reader, writer.get());
    if (lease_ns > 0) {
      const std::int64_t alive = owner.host_alive_ns(); // not what came from other hosts
      if (alive != alive_seen) {
        dds_assert_liveliness(writer.get());
        alive_seen = alive;
      }
    }
  }
  apply_counts();
  return relayed;
}

// The peers on other hosts, as DDS matched them, into the ring's counts (the node's own reader
// and writer of the topic are not peers).
void TopicBridge::Relay::apply_counts() {
  if (recount.exchange(false)) {
    const std::int32_t readers =
        writer ? count_except(writer.get(), /*publications=*/false, own_reader.load()) : 0;
    owner.count_remote_readers(readers - readers_counted);
    readers_counted = readers;
    const std::int32_t writers =
        reader ? count_except(reader.get(), /*publications=*/true, own_writer.load()) : 0;
    owner.count_remote_writers(writers - writers_counted);
    writers_counted = writers;
  }
  const std::int32_t alive = reader ? std::max(0, alive_now.load() - own_alive.load()) : 0;
  owner.count_remote_alive(alive - alive_counted);
  alive_counted = alive;
  if (const auto lost = lost_pending.exchange(0); lost > 0)
    owner.count_writers_lost(lost);
}

void TopicBridge::Relay::uncount() {
  owner.count_remote_readers(-readers_counted);
  owner.count_remote_writers(-writers_counted);
  owner.count_remote_alive(-alive_counted);
  readers_counted = writers_counted = alive_counted = 0;
}

TopicBridge::TopicBridge(std::shared_ptr<dds::Participant> participant, const shm::Arena &arena,
                         std::uint64_t doorbell)
    : participant_(std::move(participant)), arena_(arena), doorbell_(doorbell) {}

Expected<std::unique_ptr<TopicBridge>>
TopicBridge::start(std::shared_ptr<dds::Participant> participant, const shm::Arena &arena,
                   std::uint64_t doorbell) {
  if (arena.object<shm::Doorbell>(doorbell) == nullptr)
    return make_error({"node", 0, 0}, "relay", "no doorbell in the host's arena for the relay");
  std::unique_ptr<TopicBridge> bridge(new TopicBridge(std::move(participant), arena, doorbell));
  bridge->thread_ = std::thread([b = bridge.get()] { b->run(); });
  // Named, so that its CPU (it spins after data) can be told from the node's other threads.
  pthread_setname_np(bridge->thread_.native_handle(), "rsca-relay");
  return bridge;
}

TopicBridge::~TopicBridge() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  shm::ring(*arena_.object<shm::Doorbell>(doorbell_), shm::kWakeData, /*shared=*/true);
  if (thread_.joinable())
    thread_.join();
  std::lock_guard lock(mutex_);
  for (auto &[topic, relay] : relays_) {
    std::lock_guard relay_lock(relay->lock);
    relay->closed = true;
    relay->uncount();
  }
  relays_.clear();
}

int TopicBridge::sleep_ms() const {
  // A relay asserting liveliness by hand looks at the ring's writers three times a lease.
  std::int64_t ms = 1000;
  for (const auto &[topic, relay] : relays_)
    if (const std::int64_t lease = relay->lease_ns.load(); lease > 0)
      ms = std::min<std::int64_t>(ms, std::max<std::int64_t>(1, lease / 3'000'000));
  return static_cast<int>(ms);
}

void TopicBridge::run() {
  shm::SpinWait wait(*arena_.object<shm::Doorbell>(doorbell_), /*shared=*/true, relay_spin_time());
  int timeout_ms = 1000;
  bool relayed = false; // the last round relayed records out: the thread spins before it sleeps
  std::vector<std::shared_ptr<Relay>> relays;
  for (;;) {
    wait.wait(relayed, timeout_ms);
    relayed = false;
    relays.clear();
    {
      std::lock_guard lock(mutex_);
      if (stopping_)
        return;
      for (auto &[topic, relay] : relays_)
        relays.push_back(relay);
      timeout_ms = sleep_ms();
    }
    for (auto &relay : relays) { // each on its own lock: a close waits for its relay only
      std::lock_guard lock(relay->lock);
      if (!relay->closed && relay->pump() > 0)
        relayed = true;
    }
  }
}

namespace {

// An entity a DDS create call returned, and its instance handle: how its peers' statuses and
// samples name it (the relay skips its own).
tl::expected<std::pair<dds::Entity, dds_instance_handle_t>, std::string>
created(dds_entity_t result, const std::string &what) {
  auto entity = dds::checked(result, what);
  if (!entity)
    return tl::unexpected(entity.error().to_string());
  dds_instance_handle_t handle = 0;
  dds_get_instance_handle(entity->get(), &handle);
  return std::pair{std::move(*entity), handle};
}

tl::expected<dds::Qos, std::string> relay_qos(const RelayRoute &route) {
  auto qos = dds::qos_from_json(route.qos);
  if (!qos)
    return tl::unexpected(qos.error().to_string());
  return std::move(*qos);
}

tl::expected<void, std::string> open_out(TopicBridge::Relay &r, dds_entity_t participant,
                                         const shm::Arena &arena, std::uint64_t doorbell,
                                         const RelayRoute &route, port::PortType type) {
  auto qos = relay_qos(route);
  if (!qos)
    return tl::unexpected(qos.error());
  // The ring's writers say when they are alive; the relay's writer says it for them on DDS.
  dds_liveliness_kind_t kind = DDS_LIVELINESS_AUTOMATIC;
  dds_duration_t lease = DDS_INFINITY;
  dds_qget_liveliness(qos->get(), &kind, &lease);
  if (lease != DDS_INFINITY) {
    dds_qset_liveliness(qos->get(), DDS_LIVELINESS_MANUAL_BY_TOPIC, lease);
    r.lease_ns = lease;
  }
  auto slot = r.owner.claim_reader(shm::Count::Relay);
  if (!slot)
    return tl::unexpected(fmt::format("topic {} has {} same-host readers, the most a ring has",
                                      route.topic, shm::kMaxRingReaders));
  r.slot = *slot;
  auto ring = shm::RingReader::open(arena, route.ring, *slot, doorbell, 0, /*skip_relayed=*/true);
  if (!ring)
    return tl::unexpected(ring.error());
  r.ring_reader.emplace(std::move(*ring));
  r.out_convert = component::RecordRelay::of(type);
  Listener listener(dds_create_listener(&r));
  dds_lset_publication_matched(listener.get(), on_publication_matched);
  auto writer = created(dds_create_writer(participant, r.topic.get(), qos->get(), listener.get()),
                        fmt::format("creating the relay's writer on topic \"{}\"", route.topic));
  if (!writer)
    return tl::unexpected(writer.error());
  r.own_writer.store(writer->second);
  r.writer = std::move(writer->first);
  r.recount.store(true);
  return {};
}

tl::expected<void, std::string> open_in(TopicBridge::Relay &r, dds_entity_t participant,
                                        const shm::Arena &arena, const RelayRoute &route,
                                        port::PortType type) {
  auto qos = relay_qos(route);
  if (!qos)
    return tl::unexpected(qos.error());
  auto ring = shm::RingWriter::open(arena, route.ring, shm::Origin::Relayed);
  if (!ring)
    return tl::unexpected(ring.error());
  r.ring_writer.emplace(std::move(*ring));
  r.alive_now.store(0); // of an earlier reader of the topic's, if any
  r.own_alive.store(0);
  r.lost_pending.store(0);
  r.in_convert = component::RecordRelay::of(type);
  Listener listener(dds_create_listener(&r));
  dds_lset_data_available(listener.get(), on_data_available);
  dds_lset_subscription_matched(listener.get(), on_subscription_matched);
  dds_lset_liveliness_changed(listener.get(), on_liveliness_changed);
  auto reader = created(dds_create_reader(participant, r.topic.get(), qos->get(), listener.get()),
                        fmt::format("creating the relay's reader on topic \"{}\"", route.topic));
  if (!reader)
    return tl::unexpected(reader.error());
  r.own_reader.store(reader->second);
  r.reader = std::move(reader->first);
  r.recount.store(true);
  return {};
}

} // namespace

tl::expected<void, std::string> TopicBridge::open(const RelayRoute &route, shm::RingOwner owner) {
  const auto type = port::port_type_for_repid(route.repid);
  if (!type)
    return tl::unexpected(
        fmt::format("topic {}: port type {} has no DDS type to relay", route.topic, route.repid));
  std::lock_guard lock(mutex_);
  auto &slot = relays_[route.topic];
  if (!slot)
    slot = std::make_shared<Relay>(owner, arena_.object<shm::Doorbell>(doorbell_));
  Relay &r = *slot;
  std::unique_lock relay_lock(r.lock);
  if (!r.topic) {
    auto topic = dds::checked(dds_create_topic(participant_->get(),
                                               component::RecordRelay::of(*type)->descriptor(),
                                               route.topic.c_str(), nullptr, nullptr),
                              fmt::format("creating topic \"{}\"", route.topic));
    if (!topic) {
      relay_lock.unlock();
      relays_.erase(route.topic);
      return tl::unexpected(topic.error().to_string());
    }
    r.topic = std::move(*topic);
  }
  auto opened = route.outbound ? open_out(r, participant_->get(), arena_, doorbell_, route, *type)
                               : open_in(r, participant_->get(), arena_, route, *type);
  if (!opened) {
    relay_lock.unlock();
    close_locked(route.topic, route.outbound);
    return opened;
  }
  spdlog::debug("relay: topic {} {} other hosts", route.topic, route.outbound ? "to" : "from");
  shm::ring(*r.bell, shm::kWakeData, /*shared=*/true); // count what matched meanwhile
  return {};
}

std::size_t TopicBridge::relays() const {
  std::lock_guard lock(mutex_);
  std::size_t n = 0;
  for (const auto &[topic, relay] : relays_) {
    std::lock_guard relay_lock(relay->lock);
    n += (relay->writer ? 1 : 0) + (relay->reader ? 1 : 0);
  }
  return n;
}

void TopicBridge::close(const std::string &topic, bool outbound) {
  std::lock_guard lock(mutex_);
  close_locked(topic, outbound);
}

void TopicBridge::close_locked(const std::string &topic, bool outbound) {
  auto it = relays_.find(topic);
  if (it == relays_.end())
    return;
  Relay &r = *it->second;
  std::unique_lock relay_lock(r.lock);
  if (outbound) {
    r.writer.reset();
    r.ring_reader.reset();
    if (r.slot < shm::kMaxRingReaders)
      r.owner.release_reader(r.slot, shm::Count::Relay);
    r.slot = shm::kMaxRingReaders;
    r.own_writer.store(0);
    r.lease_ns = 0;
  } else {
    r.reader.reset(); // waits for its listener to return
    r.ring_writer.reset();
    r.own_reader.store(0);
  }
  r.recount.store(true);
  r.apply_counts();
  if (r.idle()) {
    r.closed = true;
    r.uncount();
    relay_lock.unlock();
    relays_.erase(it); // the thread may hold it a while yet: closed, it touches nothing
  }
}

} // namespace rsca::node
