#include "node/topic_tap.hpp"

#include <optional>
#include <vector>

#include <pthread.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "component/port_types.hpp"
#include "component/record_relay.hpp"
#include "dds/port_qos.hpp"
#include "protocol/node_ops.hpp"
#include "protocol/topics.hpp"

namespace rsca::node {

namespace {

// How often the thread looks for taps whose lease passed when no record wakes it.
constexpr int kLeaseCheckMs = 200;

} // namespace

struct TopicTaps::Tap {
  explicit Tap(shm::RingOwner ring_owner) : owner(ring_owner) {}
  ~Tap() { // the writer before the ring reader's slot goes
    writer.reset();
    reader.reset();
    if (slot < shm::kMaxRingReaders)
      owner.release_reader(slot, shm::Count::Relay);
  }
  Tap(const Tap &) = delete;
  Tap &operator=(const Tap &) = delete;

  shm::RingOwner owner;
  std::uint32_t slot = shm::kMaxRingReaders;
  std::optional<shm::RingReader> reader;
  std::unique_ptr<component::RecordRelay> convert;
  dds::Entity topic;
  dds::Entity writer;
  std::string tap_topic;
  std::chrono::steady_clock::time_point expires;
};

TopicTaps::TopicTaps(std::shared_ptr<dds::Participant> participant, const shm::Arena &arena,
                     std::uint64_t doorbell)
    : participant_(std::move(participant)), arena_(arena), doorbell_(doorbell) {}

Expected<std::unique_ptr<TopicTaps>> TopicTaps::start(std::shared_ptr<dds::Participant> participant,
                                                      const shm::Arena &arena,
                                                      std::uint64_t doorbell) {
  auto *bell = arena.object<shm::Doorbell>(doorbell);
  if (bell == nullptr)
    return make_error({"node", 0, 0}, "tap", "no doorbell in the host's arena for the taps");
  std::unique_ptr<TopicTaps> taps(new TopicTaps(std::move(participant), arena, doorbell));
  taps->thread_ =
      std::jthread([t = taps.get(), bell](std::stop_token stop) { t->run(*bell, stop); });
  pthread_setname_np(taps->thread_.native_handle(), "rsca-tap");
  return taps;
}

// The thread first (it pumps the taps), then the taps.
TopicTaps::~TopicTaps() {
  thread_.request_stop();
  shm::ring(*arena_.object<shm::Doorbell>(doorbell_), shm::kWakeData, /*shared=*/true);
  thread_.join();
}

// Each round: the taps whose viewer stopped renewing go, the others copy what their ring has.
// The copy is a best-effort DDS write: it never waits for a viewer.
void TopicTaps::run(shm::Doorbell &bell, const std::stop_token &stop) {
  while (!stop.stop_requested()) {
    shm::sleep(bell, kLeaseCheckMs, /*shared=*/true);
    shm::take(bell);
    std::lock_guard lock(mutex_);
    const auto now = std::chrono::steady_clock::now();
    for (auto it = taps_.begin(); it != taps_.end();) {
      if (it->second->expires <= now) {
        spdlog::info("tap of topic {} closed: its viewer stopped renewing it", it->first);
        it = taps_.erase(it);
        continue;
      }
      it->second->convert->to_dds(*it->second->reader, it->second->writer.get());
      ++it;
    }
  }
}

namespace {

tl::expected<void, std::string> open_tap(TopicTaps::Tap &t, dds_entity_t participant,
                                         const shm::Arena &arena, std::uint64_t doorbell,
                                         const TapRoute &route, port::PortType type) {
  auto qos = dds::qos_from_json(protocol::node::tap_qos());
  if (!qos)
    return tl::unexpected(qos.error().to_string());
  auto slot = t.owner.claim_reader(shm::Count::Relay);
  if (!slot)
    return tl::unexpected(fmt::format("topic {} has {} same-host readers, the most a ring has",
                                      route.topic, shm::kMaxRingReaders));
  t.slot = *slot;
  // From what arrives next; relayed records too: the viewer sees what the topic carries here.
  auto ring = shm::RingReader::open(arena, route.ring, *slot, doorbell, 0);
  if (!ring)
    return tl::unexpected(ring.error());
  t.reader.emplace(std::move(*ring));
  t.convert = component::RecordRelay::of(type);
  t.tap_topic = protocol::tap_topic(route.topic);
  auto topic = dds::checked(
      dds_create_topic(participant, t.convert->descriptor(), t.tap_topic.c_str(), nullptr, nullptr),
      fmt::format("creating topic \"{}\"", t.tap_topic));
  if (!topic)
    return tl::unexpected(topic.error().to_string());
  t.topic = std::move(*topic);
  auto writer = dds::checked(dds_create_writer(participant, t.topic.get(), qos->get(), nullptr),
                             fmt::format("creating the tap's writer on \"{}\"", t.tap_topic));
  if (!writer)
    return tl::unexpected(writer.error().to_string());
  t.writer = std::move(*writer);
  return {};
}

} // namespace

tl::expected<std::string, std::string> TopicTaps::open(const TapRoute &route,
                                                       shm::RingOwner owner) {
  const auto type = port::port_type_for_repid(route.repid);
  if (!type)
    return tl::unexpected(
        fmt::format("topic {}: port type {} has no DDS type to show", route.topic, route.repid));
  std::lock_guard lock(mutex_);
  const auto expires = std::chrono::steady_clock::now() + route.lease;
  if (auto found = taps_.find(route.topic); found != taps_.end()) {
    found->second->expires = std::max(found->second->expires, expires);
    return found->second->tap_topic;
  }
  auto tap = std::make_unique<Tap>(owner);
  if (auto opened = open_tap(*tap, participant_->get(), arena_, doorbell_, route, *type); !opened)
    return tl::unexpected(opened.error());
  tap->expires = expires;
  spdlog::info("tap of topic {} opened on {} for {} ms", route.topic, tap->tap_topic,
               route.lease.count());
  std::string name = tap->tap_topic;
  taps_.emplace(route.topic, std::move(tap));
  return name;
}

void TopicTaps::close(const std::string &topic) {
  std::lock_guard lock(mutex_);
  if (taps_.erase(topic) > 0)
    spdlog::info("tap of topic {} closed: its ring goes", topic);
}

std::size_t TopicTaps::taps() const {
  std::lock_guard lock(mutex_);
  return taps_.size();
}

} // namespace rsca::node
