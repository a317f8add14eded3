// The node's relay of rings to and from other hosts (node/topic_bridge.hpp), on real DDS: two
// "hosts" in one process, each an arena with a ring of the topic and a bridge on a participant of
// its own. What one host writes into its ring reaches the other's ring, in order, once; each ring
// counts the peer the other bridge matched; closing a relay takes its counts back.
#include <catch2/catch.hpp>

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <new>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

#include "component/port_record.hpp"
#include "component/port_types.hpp"
#include "eventually.hpp"
#include "node/topic_bridge.hpp"
#include "shm/arena.hpp"
#include "shm/doorbell.hpp"
#include "shm/ring.hpp"
#include "test_domain.hpp"

using namespace rsca;

using rsca::test::eventually;

namespace {

// One host's data: its arena, a doorbell for its bridge and one for its reader, the topic's ring.
struct Host {
  shm::Arena arena = shm::Arena::create(8 << 20).value();
  shm::ArenaAllocator allocator{arena.size()};
  std::uint64_t bridge_bell = doorbell();
  std::uint64_t reader_bell = doorbell();
  std::uint64_t ring_at = allocator.allocate(shm::ring_bytes({})).value();
  shm::RingOwner owner = shm::RingOwner::create(arena, ring_at, {}).value();
  std::unique_ptr<node::TopicBridge> bridge;

  explicit Host(std::shared_ptr<dds::Participant> participant) {
    auto started = node::TopicBridge::start(std::move(participant), arena, bridge_bell);
    REQUIRE(started.has_value());
    bridge = std::move(*started);
  }
  std::uint64_t doorbell() {
    const auto at = allocator.allocate(sizeof(shm::Doorbell)).value();
    new (arena.at(at, sizeof(shm::Doorbell))) shm::Doorbell();
    return at;
  }
  node::RelayRoute route(const std::string &topic, bool outbound) const {
    return {topic, ring_at, outbound, "IDL:rsca/SampleSeq:1.0",
            nlohmann::json{{"reliability", "reliable"}, {"history", "keeplast"}, {"depth", 16}}};
  }
};

std::vector<std::uint64_t> take_sequences(shm::RingReader &reader) {
  std::vector<std::uint64_t> out;
  port::Samples s;
  reader.take(
      [&s](const std::byte *at, std::size_t bytes) {
        port::record::Reader r(at, bytes);
        return port::record::read(r, s);
      },
      [&] { out.push_back(s.sequence); });
  return out;
}

tl::expected<void, std::string> write_sample(shm::RingWriter &writer, std::uint64_t sequence) {
  port::Samples s;
  s.sequence = sequence;
  s.stream_id = "bridge";
  s.samples = {static_cast<double>(sequence)};
  return writer.write(port::record::size_of(s), [&s](std::byte *at) {
    port::record::Writer w(at);
    port::record::write(s, w);
  });
}

} // namespace

TEST_CASE("relay: a host's records reach the other host's ring in order through the two bridges, "
          "peers are counted, and a closed relay takes its counts back",
          "[node][relay][dds]") {
  Host a(test::participant()), b(test::participant());
  const std::string topic = "rsca_test_bridge_" + std::to_string(::getpid());
  REQUIRE(a.bridge->open(a.route(topic, /*outbound=*/true), a.owner).has_value());
  REQUIRE(b.bridge->open(b.route(topic, /*outbound=*/false), b.owner).has_value());
  CHECK(a.bridge->relays() == 1);
  CHECK(b.bridge->relays() == 1);

  // A's own writer and B's own reader, as a component of each host would have them.
  a.owner.add_writer();
  auto writer = shm::RingWriter::open(a.arena, a.ring_at).value();
  const auto slot = b.owner.claim_reader().value();
  auto reader = shm::RingReader::open(b.arena, b.ring_at, slot, b.reader_bell, 0).value();

  // Each ring counts the peer the other host's bridge is: B's DDS reader for A's writer, A's
  // DDS writer for B's reader.
  REQUIRE(eventually([&] { return writer.readers() == 1; }));
  REQUIRE(eventually([&] { return reader.writers() == 1; }));

  for (std::uint64_t n = 1; n <= 20; ++n)
    REQUIRE(write_sample(writer, n).has_value());
  std::vector<std::uint64_t> got;
  REQUIRE(eventually([&] {
    for (auto n : take_sequences(reader))
      got.push_back(n);
    return got.size() >= 20;
  }));
  std::vector<std::uint64_t> expected;
  for (std::uint64_t n = 1; n <= 20; ++n)
    expected.push_back(n);
  CHECK(got == expected);

  // Closing A's relay out: B's ring no longer counts a writer on another host, A's no reader.
  a.bridge->close(topic, /*outbound=*/true);
  CHECK(a.bridge->relays() == 0);
  REQUIRE(eventually([&] { return reader.writers() == 0; }));
  CHECK(writer.readers() == 0);
  b.bridge->close(topic, /*outbound=*/false);
  CHECK(b.bridge->relays() == 0);
  CHECK(take_sequences(reader).empty()); // nothing more, nothing twice
}

TEST_CASE("relay: what a bridge relayed into its host's ring is not relayed back out",
          "[node][relay][dds]") {
  // Both hosts relay the topic both ways (an event channel with members on both): a record
  // written on A arrives on B once and never comes back to A.
  Host a(test::participant()), b(test::participant());
  const std::string topic = "rsca_test_bridge_echo_" + std::to_string(::getpid());
  for (Host *h : {&a, &b}) {
    REQUIRE(h->bridge->open(h->route(topic, true), h->owner).has_value());
    REQUIRE(h->bridge->open(h->route(topic, false), h->owner).has_value());
  }
  a.owner.add_writer();
  auto writer = shm::RingWriter::open(a.arena, a.ring_at).value();
  auto a_reader =
      shm::RingReader::open(a.arena, a.ring_at, a.owner.claim_reader().value(), a.reader_bell, 0)
          .value();
  auto b_reader =
      shm::RingReader::open(b.arena, b.ring_at, b.owner.claim_reader().value(), b.reader_bell, 0)
          .value();
  // Each side's writer counts the other's DDS reader; its own reader of the topic is not a peer.
  REQUIRE(eventually([&] { return writer.readers() == 2; })); // A's own reader and B's bridge
  REQUIRE(eventually([&] { return b_reader.writers() == 1; }));

  REQUIRE(write_sample(writer, 7).has_value());
  std::vector<std::uint64_t> on_b;
  REQUIRE(eventually([&] {
    for (auto n : take_sequences(b_reader))
      on_b.push_back(n);
    return !on_b.empty();
  }));
  // A round trip's time more for an echo to come back, had there been one: B's bridge relays out
  // only what B's host wrote, so A's ring holds its own record alone.
  REQUIRE(write_sample(writer, 8).has_value());
  REQUIRE(eventually([&] {
    for (auto n : take_sequences(b_reader))
      on_b.push_back(n);
    return on_b.size() >= 2;
  }));
  CHECK(on_b == std::vector<std::uint64_t>{7, 8});
  CHECK(take_sequences(a_reader) == std::vector<std::uint64_t>{7, 8});
  for (Host *h : {&a, &b}) {
    h->bridge->close(topic, true);
    h->bridge->close(topic, false);
    CHECK(h->bridge->relays() == 0);
  }
}
