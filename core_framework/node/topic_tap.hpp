// Taps of the host's rings for viewers (rsca echo, rsca hz; issue 39 item 9): a copy of a
// topic's records on a DDS topic of its own (protocol::tap_topic), best effort and keep-last
// (protocol::node::tap_qos), open while its viewer renews it (node.tap).
//
// Why this way: a same-host connection's records never reach DDS, so only the node, which owns
// the ring, can show them; and a viewer must not disturb what it looks at. The tap reads the ring
// as the relay does, with a reader slot that counts as no peer (the connection's matched counts
// do not change), and a ring writer never waits for a reader: a tap that falls behind loses
// records, the connection does not. Its DDS writer is best effort: a viewer that stops reading,
// or dies, never holds it either, and its lease closes the tap soon after.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <stop_token>
#include <string>
#include <thread>

#include <tl/expected.hpp>

#include "common/diagnostic.hpp"
#include "dds/participant.hpp"
#include "shm/arena.hpp"
#include "shm/doorbell.hpp"
#include "shm/ring.hpp"

namespace rsca::node {

// A tap as the host's data asks for it.
struct TapRoute {
  std::string topic;
  std::uint64_t ring = 0; // its offset in the host's arena
  std::string repid;
  std::chrono::milliseconds lease{0};
};

class TopicTaps {
public:
  // Taps rings of `arena` (which must outlive it) over `participant`; its thread sleeps on the
  // doorbell at `doorbell` in the arena.
  static Expected<std::unique_ptr<TopicTaps>> start(std::shared_ptr<dds::Participant> participant,
                                                    const shm::Arena &arena,
                                                    std::uint64_t doorbell);
  ~TopicTaps();
  TopicTaps(const TopicTaps &) = delete;
  TopicTaps &operator=(const TopicTaps &) = delete;

  // Opens the tap of `route.topic`, or renews it, until `route.lease` passes: its DDS topic.
  tl::expected<std::string, std::string> open(const TapRoute &route, shm::RingOwner owner);
  // The tap of `topic` goes (its ring is about to be freed); nothing if there is none.
  void close(const std::string &topic);
  std::size_t taps() const;

  struct Tap; // node/topic_tap.cpp

private:
  TopicTaps(std::shared_ptr<dds::Participant> participant, const shm::Arena &arena,
            std::uint64_t doorbell);
  void run(shm::Doorbell &bell, const std::stop_token &stop);

  std::shared_ptr<dds::Participant> participant_;
  const shm::Arena &arena_;
  std::uint64_t doorbell_;
  mutable std::mutex mutex_; // guards taps_ against the thread, which pumps them under it
  std::map<std::string, std::unique_ptr<Tap>> taps_; // by the connection's topic
  std::jthread thread_;
};

} // namespace rsca::node
