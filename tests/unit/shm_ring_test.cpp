// The host's shared memory for same-host data (shm/): the arena's allocator, a topic's ring with
// its writers, readers, depths and overruns, its doorbells, and a ring between two processes.
#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
#include <cstring>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include "component/port_record.hpp"
#include "eventually.hpp"
#include "shm/arena.hpp"
#include "shm/doorbell.hpp"
#include "shm/ring.hpp"

using namespace rsca;

using rsca::test::eventually;

namespace {

// A record of one 64-bit number, for ring tests.
tl::expected<void, std::string> write_number(shm::RingWriter &writer, std::uint64_t n) {
  return writer.write(sizeof(n), [n](std::byte *at) { std::memcpy(at, &n, sizeof(n)); });
}

std::vector<std::uint64_t> take_numbers(shm::RingReader &reader) {
  std::vector<std::uint64_t> out;
  std::uint64_t n = 0;
  reader.take(
      [&n](const std::byte *at, std::size_t bytes) {
        if (bytes != sizeof(n))
          return false;
        std::memcpy(&n, at, sizeof(n));
        return true;
      },
      [&] { out.push_back(n); });
  return out;
}

// What a reader of a ring of `most` records took after a writer wrote up to `last`: the newest
// records, in order, ending at `last`, none torn or repeated.
void check_newest_in_order(const std::vector<std::uint64_t> &got, std::uint64_t last,
                           std::size_t most) {
  REQUIRE_FALSE(got.empty());
  CHECK(got.size() <= most);
  CHECK(got.back() == last);
  for (std::size_t i = 1; i < got.size(); ++i)
    CHECK(got[i] == got[i - 1] + 1);
}

struct RingFixture {
  shm::Arena arena = shm::Arena::create(8 << 20).value();
  shm::ArenaAllocator allocator{arena.size()};
  std::uint64_t bell_at = allocator.allocate(sizeof(shm::Doorbell)).value();
  shm::Doorbell *bell = new (arena.at(bell_at, sizeof(shm::Doorbell))) shm::Doorbell();

  std::pair<shm::RingOwner, std::uint64_t> make(shm::RingLimits limits = {}) {
    const auto at = allocator.allocate(shm::ring_bytes(limits)).value();
    return {shm::RingOwner::create(arena, at, limits).value(), at};
  }
  shm::RingReader reader(shm::RingOwner &owner, std::uint64_t at, std::uint32_t depth = 0) {
    const auto slot = owner.claim_reader().value();
    return shm::RingReader::open(arena, at, slot, bell_at, depth).value();
  }
};

// The node's relay thread, reduced to its wait (node/topic_bridge.cpp): it waits on the bell with
// a SpinWait, spinning after a round that took records, and takes what the ring has.
struct RelayThread {
  RingFixture &f;
  shm::RingReader reader;
  shm::SpinWait wait;
  std::vector<std::uint64_t> got; // the thread's until it is joined
  std::atomic<std::size_t> delivered{0};
  std::atomic<bool> stopping{false};
  std::thread thread;

  RelayThread(RingFixture &fixture, shm::RingReader ring_reader, std::chrono::microseconds spin)
      : f(fixture), reader(std::move(ring_reader)), wait(*f.bell, /*shared=*/true, spin) {
    thread = std::thread([this] {
      bool took = false;
      while (!stopping.load()) {
        wait.wait(took, 1000);
        const auto numbers = take_numbers(reader);
        got.insert(got.end(), numbers.begin(), numbers.end());
        delivered.store(got.size());
        took = !numbers.empty();
      }
    });
  }
  void stop() {
    stopping = true;
    shm::ring(*f.bell, shm::kWakeData, /*shared=*/true);
    thread.join();
  }
};

} // namespace

TEST_CASE("shm: the arena's allocator gives aligned blocks, merges what is freed, and fills",
          "[shm]") {
  shm::ArenaAllocator allocator(4096);
  const auto a = allocator.allocate(100).value();
  const auto b = allocator.allocate(100).value();
  CHECK(a > 0); // offset 0 means "none" in the arena: never given out
  CHECK(a % shm::ArenaAllocator::kAlign == 0);
  CHECK(b % shm::ArenaAllocator::kAlign == 0);
  CHECK(b >= a + 100);
  CHECK(allocator.in_use() == 256);
  CHECK_FALSE(allocator.allocate(4096).has_value());
  allocator.release(a);
  allocator.release(b);
  CHECK(allocator.in_use() == 0);
  CHECK(allocator.allocate(4096 - shm::ArenaAllocator::kAlign).has_value()); // one block again
}

TEST_CASE("shm: an arena grant reads back, and a malformed one is refused", "[shm]") {
  const shm::ArenaGrant grant{4, 65536, 4096};
  const auto back = shm::ArenaGrant::parse(grant.to_string());
  REQUIRE(back.has_value());
  CHECK(back->page == 65536);
  CHECK(back->page_bytes == 4096);
  CHECK_FALSE(shm::ArenaGrant::parse("4:65536").has_value());
  CHECK_FALSE(shm::ArenaGrant::parse("4:1:2:3").has_value());
  CHECK_FALSE(shm::ArenaGrant::parse("x").has_value());
}

TEST_CASE("shm: a ring delivers in order what is written after its reader opened, and rings it",
          "[shm]") {
  RingFixture f;
  auto [owner, at] = f.make();
  auto writer = shm::RingWriter::open(f.arena, at).value();
  owner.add_writer();
  REQUIRE(write_number(writer, 99)); // before the reader: not seen
  auto reader = f.reader(owner, at);
  CHECK(writer.readers() == 1);
  CHECK(reader.writers() == 1);
  for (std::uint64_t i = 0; i < 10; ++i)
    REQUIRE(write_number(writer, i));
  CHECK((shm::take(*f.bell) & shm::kWakeNearData) != 0);
  const auto got = take_numbers(reader);
  REQUIRE(got.size() == 10);
  for (std::uint64_t i = 0; i < 10; ++i)
    CHECK(got[i] == i);
  CHECK(reader.dropped() == 0);
  CHECK(take_numbers(reader).empty());
}

TEST_CASE("shm: a reader of depth n takes the newest n and counts the rest dropped", "[shm]") {
  RingFixture f;
  auto [owner, at] = f.make();
  auto writer = shm::RingWriter::open(f.arena, at).value();
  auto reader = f.reader(owner, at, /*depth=*/2);
  for (std::uint64_t i = 0; i < 5; ++i)
    REQUIRE(write_number(writer, i));
  CHECK(take_numbers(reader) == std::vector<std::uint64_t>{3, 4});
  CHECK(reader.dropped() == 3);
}

TEST_CASE("shm: a transient-local reader starts at the last records the ring still holds",
          "[shm][qos]") {
  RingFixture f;
  auto [owner, at] = f.make({4096, 16});
  auto writer = shm::RingWriter::open(f.arena, at).value();
  for (std::uint64_t i = 0; i < 5; ++i)
    REQUIRE(write_number(writer, i));
  // History 3 of 5 written: the last three, then what comes.
  auto late = shm::RingReader::open(f.arena, at, owner.claim_reader().value(), f.bell_at, 0,
                                    /*skip_relayed=*/false, /*history=*/3)
                  .value();
  REQUIRE(write_number(writer, 5));
  CHECK(take_numbers(late) == std::vector<std::uint64_t>{2, 3, 4, 5});
  CHECK(late.dropped() == 0);
  // More history than the ring holds: what it holds (16 records), none overwritten delivered.
  for (std::uint64_t i = 6; i < 40; ++i)
    REQUIRE(write_number(writer, i));
  auto all = shm::RingReader::open(f.arena, at, owner.claim_reader().value(), f.bell_at, 0,
                                   /*skip_relayed=*/false, /*history=*/1000)
                 .value();
  check_newest_in_order(take_numbers(all), 39, 16);
}

TEST_CASE("shm: a writer never waits: a reader that fell behind loses the oldest, never a torn "
          "one",
          "[shm]") {
  RingFixture f;
  auto [owner, at] = f.make({4096, 16});
  auto writer = shm::RingWriter::open(f.arena, at).value();
  auto reader = f.reader(owner, at);
  for (std::uint64_t i = 0; i < 100; ++i)
    REQUIRE(write_number(writer, i));
  const auto got = take_numbers(reader);
  check_newest_in_order(got, 99, 16);
  CHECK(reader.dropped() + got.size() == 100);
  // A record larger than half the ring is refused, and nothing is published.
  CHECK_FALSE(writer.write(4096, [](std::byte *) {}).has_value());
  CHECK(take_numbers(reader).empty());
}

TEST_CASE("shm: a ring has at most kMaxRingReaders readers, a slot released is claimed again",
          "[shm]") {
  RingFixture f;
  auto [owner, at] = f.make();
  std::vector<std::uint32_t> slots;
  for (std::uint32_t i = 0; i < shm::kMaxRingReaders; ++i)
    slots.push_back(owner.claim_reader().value());
  CHECK_FALSE(owner.claim_reader().has_value());
  owner.release_reader(slots[7]);
  CHECK(owner.claim_reader() == slots[7]);
  // A reader opens only the slot claimed for it.
  owner.release_reader(slots[3]);
  CHECK_FALSE(shm::RingReader::open(f.arena, at, slots[3], f.bell_at, 0).has_value());
  CHECK_FALSE(shm::RingReader::open(f.arena, at + 64, 0, f.bell_at, 0).has_value());
}

TEST_CASE("shm: a writer's process that ends is counted lost, and liveliness is its last write",
          "[shm]") {
  RingFixture f;
  auto [owner, at] = f.make();
  auto writer = shm::RingWriter::open(f.arena, at).value();
  auto reader = f.reader(owner, at);
  owner.add_writer();
  CHECK(reader.alive_ns() == 0);
  REQUIRE(write_number(writer, 1));
  const auto first = reader.alive_ns();
  CHECK(first > 0);
  writer.assert_alive();
  CHECK(reader.alive_ns() >= first);
  owner.remove_writer(/*lost=*/true);
  CHECK(reader.writers() == 0);
  CHECK(reader.writers_lost() == 1);
}

TEST_CASE("shm: the node's relay reads what the host wrote, never what it relayed in, and is "
          "no peer",
          "[shm]") {
  RingFixture f;
  auto [owner, at] = f.make();
  auto host = shm::RingWriter::open(f.arena, at).value();
  auto relayed_in = shm::RingWriter::open(f.arena, at, shm::Origin::Relayed).value();
  auto process = f.reader(owner, at);
  const auto relay_slot = owner.claim_reader(shm::Count::Relay).value();
  auto relay_out = shm::RingReader::open(f.arena, at, relay_slot, f.bell_at, 0,
                                         /*skip_relayed=*/true)
                       .value();
  CHECK(host.readers() == 1); // the process only
  REQUIRE(write_number(host, 1));
  REQUIRE(write_number(relayed_in, 2));
  REQUIRE(write_number(host, 3));
  CHECK(take_numbers(process) == std::vector<std::uint64_t>{1, 2, 3});
  CHECK(take_numbers(relay_out) == std::vector<std::uint64_t>{1, 3});
  CHECK(relay_out.dropped() == 0); // skipped, not lost
  // Peers on other hosts are counted as DDS matches them, and taken back.
  owner.count_remote_readers(2);
  owner.count_remote_writers(1);
  owner.count_remote_alive(1);
  CHECK(host.readers() == 3);
  CHECK(process.writers() == 1);
  CHECK(process.remote_alive() == 1);
  owner.count_remote_readers(-2);
  owner.count_remote_writers(-1);
  owner.count_remote_alive(-1);
  owner.count_writers_lost(1);
  CHECK(host.readers() == 1);
  CHECK(process.writers() == 0);
  CHECK(process.writers_lost() == 1);
  owner.release_reader(relay_slot, shm::Count::Relay);
  CHECK(host.readers() == 1);
}

TEST_CASE("shm: a ring carries records between two processes, the reader asleep on its doorbell",
          "[shm]") {
  RingFixture f;
  auto [owner, at] = f.make({1 << 16, 1024});
  auto reader = f.reader(owner, at);
  constexpr std::uint64_t kRecords = 20000;
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    // The child maps the arena anew, from its descriptor, as a process its node started would.
    auto mapped = shm::Arena::map(rsca::process::Fd(::dup(f.arena.fd())));
    if (!mapped)
      ::_exit(2);
    auto writer = shm::RingWriter::open(*mapped, at);
    if (!writer)
      ::_exit(3);
    for (std::uint64_t i = 0; i < kRecords; ++i)
      if (!write_number(*writer, i))
        ::_exit(4);
    ::_exit(0);
  }
  std::vector<std::uint64_t> got;
  while (got.size() + reader.dropped() < kRecords) {
    shm::sleep(*f.bell, 1000, /*shared=*/true);
    shm::take(*f.bell);
    for (auto n : take_numbers(reader))
      got.push_back(n);
  }
  int status = 0;
  REQUIRE(::waitpid(child, &status, 0) == child);
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  REQUIRE_FALSE(got.empty());
  CHECK(got.back() == kRecords - 1);
  for (std::size_t i = 1; i < got.size(); ++i)
    REQUIRE(got[i] > got[i - 1]);
}

TEST_CASE("shm: port values round-trip as ring records, a short record is refused", "[shm]") {
  port::Samples s;
  s.timestamp_ns = 12;
  s.sequence = 3;
  s.stream_id = "lidar";
  s.sample_rate = 10.5;
  s.complex = true;
  s.samples = {1.0, -2.5, 3.25};
  std::vector<std::byte> buffer(port::record::size_of(s));
  port::record::Writer w(buffer.data());
  port::record::write(s, w);
  port::Samples back;
  port::record::Reader r(buffer.data(), buffer.size());
  REQUIRE(port::record::read(r, back));
  CHECK(back.stream_id == "lidar");
  CHECK(back.complex);
  CHECK_FALSE(back.end_of_stream);
  CHECK(back.samples == s.samples);
  CHECK(back.sample_rate == 10.5);
  port::record::Reader short_one(buffer.data(), buffer.size() - 1);
  CHECK_FALSE(port::record::read(short_one, back));

  port::Command c{1, 2, "me", "go", {0.5}, "now"};
  std::vector<std::byte> command(port::record::size_of(c));
  port::record::Writer cw(command.data());
  port::record::write(c, cw);
  port::Command cback;
  port::record::Reader cr(command.data(), command.size());
  REQUIRE(port::record::read(cr, cback));
  CHECK(cback.name == "go");
  CHECK(cback.args == c.args);
  CHECK(cback.text == "now");
}

TEST_CASE("relay: a spinning wait takes the records written while it spins, in order, and never "
          "sleeps between them",
          "[shm][relay]") {
  RingFixture f;
  auto [owner, at] = f.make();
  auto writer = shm::RingWriter::open(f.arena, at).value();
  // A spin far longer than the test: each record is written after the last was taken, so the
  // thread is spinning when it comes; only the wait for the first may sleep.
  RelayThread relay(f, f.reader(owner, at), std::chrono::seconds(60));
  constexpr std::uint64_t kRecords = 200;
  for (std::uint64_t i = 0; i < kRecords; ++i) {
    REQUIRE(write_number(writer, i));
    REQUIRE(eventually([&] { return relay.delivered.load() == i + 1; }));
  }
  CHECK(relay.wait.sleeps() <= 1);
  relay.stop();
  REQUIRE(relay.got.size() == kRecords);
  for (std::uint64_t i = 0; i < kRecords; ++i)
    CHECK(relay.got[i] == i);
  CHECK(relay.reader.dropped() == 0);
}

TEST_CASE("relay: a spinning wait goes back to sleep when no record comes, and a ring wakes it",
          "[shm][relay]") {
  RingFixture f;
  auto [owner, at] = f.make();
  auto writer = shm::RingWriter::open(f.arena, at).value();
  RelayThread relay(f, f.reader(owner, at), std::chrono::microseconds(200));
  // Asleep before any data: it never spins then.
  REQUIRE(eventually([&] { return f.bell->sleeping.load() == 1; }));
  CHECK(relay.wait.caught() == 0);
  for (std::uint64_t round = 1; round <= 3; ++round) {
    const auto slept = relay.wait.sleeps();
    REQUIRE(write_number(writer, round));
    REQUIRE(eventually([&] { return relay.delivered.load() == round; }));
    // The spin after the record ends and the thread sleeps again on the futex.
    REQUIRE(
        eventually([&] { return relay.wait.sleeps() > slept && f.bell->sleeping.load() == 1; }));
  }
  relay.stop();
  CHECK(relay.got == std::vector<std::uint64_t>{1, 2, 3});
}

TEST_CASE("relay: a wait with no spin sleeps after data too", "[shm][relay]") {
  shm::Doorbell bell;
  shm::SpinWait wait(bell, /*shared=*/false, std::chrono::microseconds(0));
  shm::ring(bell, shm::kWakeNearData, /*shared=*/false);
  CHECK(wait.wait(true, 1000) == shm::kWakeNearData); // rung before: no sleep
  CHECK(wait.sleeps() == 0);
  CHECK(wait.wait(true, 0) == 0); // nothing rang: it slept (a timeout of 0) without spinning
  CHECK(wait.sleeps() == 1);
  CHECK(wait.caught() == 0);
}
