// The node as its host's gateway to the other hosts (issue 20, item 3): a topic with ends on
// other hosts goes component → this host's ring → the node's DDS writer → the other node's DDS
// reader → its ring → component. Only the nodes' participants are on DDS, so a launch adds
// endpoints among participants that already know each other, and an event channel is one DDS
// topic per domain that each node fans out to its host's subscribers through one ring.
//
// Per topic and direction, the node has one relay, opened with the first end that needs it and
// closed with the last (node/host_data.hpp counts the ends):
// - out: a reader of the ring (not counted as a peer, skipping what was relayed in) and a DDS
//   writer; a thread of the node wakes on its doorbell and writes each record to DDS;
// - in: a DDS reader whose listener writes each sample into the ring (Origin::Relayed), skipping
//   what this node's own writer sent.
// The peers on other hosts are counted into the ring as DDS matches them (matched counts), and
// so is their liveliness (a relay out asserts its writer's liveliness by hand, when the ring's
// writers did).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>
#include <tl/expected.hpp>

#include "common/diagnostic.hpp"
#include "dds/participant.hpp"
#include "shm/arena.hpp"
#include "shm/doorbell.hpp"
#include "shm/ring.hpp"

namespace rsca::node {

// A ring's relay to or from DDS, as the host's data asks for it.
struct RelayRoute {
  std::string topic;
  std::uint64_t ring = 0; // its offset in the host's arena
  bool outbound = false;  // the host's records out to DDS; else DDS's samples into the ring
  std::string repid;
  nlohmann::json qos; // dds/port_qos.hpp's JSON form: the connection's
};

// What the host's data needs of a relay: an interface, so that the bookkeeping is tested
// without DDS.
class TopicRelay {
public:
  virtual ~TopicRelay() = default;
  virtual tl::expected<void, std::string> open(const RelayRoute &route, shm::RingOwner owner) = 0;
  // Nothing of the ring is touched once it returns.
  virtual void close(const std::string &topic, bool outbound) = 0;
  // The relays open, a direction of a topic each.
  virtual std::size_t relays() const = 0;
};

class TopicBridge final : public TopicRelay {
public:
  // Relays rings of `arena` (which must outlive it) over `participant`; its thread sleeps on the
  // doorbell at `doorbell` in the arena.
  static Expected<std::unique_ptr<TopicBridge>> start(std::shared_ptr<dds::Participant> participant,
                                                      const shm::Arena &arena,
                                                      std::uint64_t doorbell);
  ~TopicBridge() override;
  TopicBridge(const TopicBridge &) = delete;
  TopicBridge &operator=(const TopicBridge &) = delete;

  tl::expected<void, std::string> open(const RelayRoute &route, shm::RingOwner owner) override;
  void close(const std::string &topic, bool outbound) override;
  std::size_t relays() const override;

  struct Relay; // one topic's relays, both ways (node/topic_bridge.cpp)

private:
  TopicBridge(std::shared_ptr<dds::Participant> participant, const shm::Arena &arena,
              std::uint64_t doorbell);
  void run();
  int sleep_ms() const;
  void close_locked(const std::string &topic, bool outbound);

  std::shared_ptr<dds::Participant> participant_;
  const shm::Arena &arena_;
  std::uint64_t doorbell_;
  mutable std::mutex mutex_;                             // guards relays_ against the thread
  std::map<std::string, std::shared_ptr<Relay>> relays_; // by topic
  bool stopping_ = false;
  std::thread thread_;
};

} // namespace rsca::node
