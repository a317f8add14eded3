// The node's shared memory for its host's data (node/host_data.hpp): a ring per same-host topic
// made at the first connect that asks for one, each end counted, everything freed when the ends
// go, and a process's end let go when it ends.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include "node/host_data.hpp"
#include "protocol/component_ops.hpp"
#include "shm/ring.hpp"

using namespace rsca;

namespace {

protocol::component::ConnectRequest same_host_connect(const std::string &direction,
                                                      const std::string &port) {
  protocol::component::ConnectRequest r;
  r.connection = "c1";
  r.port = port;
  r.direction = direction;
  r.repid = "IDL:T:1.0";
  r.topic = "rsca/d/app/c1";
  r.shared_memory = true;
  return r;
}

} // namespace

TEST_CASE("host data: two ends of a topic share one ring, it goes with its last end",
          "[host-data]") {
  auto data = node::HostData::create({}, 64 << 20).value();
  const auto writer = data->connect(100, "a", same_host_connect("uses", "out"));
  REQUIRE(writer.has_value());
  data->connected(100, "a", "out", "c1", true);
  const auto reader = data->connect(200, "b", same_host_connect("provides", "in"));
  REQUIRE(reader.has_value());
  data->connected(200, "b", "in", "c1", true);
  CHECK(writer->offset == reader->offset);
  CHECK(data->counts().rings == 1);
  CHECK(data->counts().ends == 2);
  // Made again, the reader gets a slot of its own while the process still reads on the old one;
  // the old one goes once the process says it made the new connection.
  const auto again = data->connect(200, "b", same_host_connect("provides", "in"));
  REQUIRE(again.has_value());
  CHECK(again->slot != reader->slot);
  CHECK(data->counts().ends == 3);
  data->connected(200, "b", "in", "c1", true);
  CHECK(data->counts().ends == 2);
  // Refused by the process, a connect made again leaves the end it had.
  REQUIRE(data->connect(100, "a", same_host_connect("uses", "out")).has_value());
  data->connected(100, "a", "out", "c1", false);
  CHECK(data->counts().ends == 2);
  CHECK(data->counts().rings == 1);
  data->disconnect(100, "a", "out", "c1");
  CHECK(data->counts().rings == 1);
  data->disconnect(200, "b", "in", "c1");
  CHECK(data->counts().rings == 0);
  CHECK(data->counts().ends == 0);
  CHECK(data->counts().bytes_in_use == 0);
}

TEST_CASE("host data: a same-host connect without its topic is refused, holding nothing",
          "[host-data]") {
  auto data = node::HostData::create({}, 64 << 20).value();
  auto no_topic = same_host_connect("uses", "out");
  no_topic.topic.reset();
  const auto refused = data->connect(100, "a", no_topic);
  REQUIRE_FALSE(refused.has_value());
  CHECK(refused.error() == "a same-host connection needs its topic");
  CHECK(data->counts().rings == 0);
  CHECK(data->counts().ends == 0);
}

TEST_CASE("host data: a process that ends lets go of its page and its ends, its readers see a "
          "lost writer",
          "[host-data]") {
  auto data = node::HostData::create({}, 64 << 20).value();
  auto page = data->reserve_page();
  REQUIRE(page.has_value());
  CHECK(page->second.starts_with("4:"));
  data->adopt(::getpid(), page->first); // a live process
  CHECK(data->counts().pages == 1);
  REQUIRE(data->connect(::getpid(), "a", same_host_connect("uses", "out")).has_value());
  data->connected(::getpid(), "a", "out", "c1", true);
  const auto reader = data->connect(200, "b", same_host_connect("provides", "in"));
  REQUIRE(reader.has_value());
  data->forget(::getpid());
  CHECK(data->counts().pages == 0);
  CHECK(data->counts().ends == 1);
  // The reader's view of the ring: no writer left, one lost.
  const auto mapped = shm::Arena::map(process::Fd(::dup(data->arena_fd()))).value();
  auto ring = shm::detail::RingView::open(mapped, reader->offset).value();
  CHECK(ring.header->writers.load() == 0);
  CHECK(ring.header->writers_lost.load() == 1);
  data->forget(200); // its end still pending: it goes too
  CHECK(data->counts().rings == 0);
  CHECK(data->counts().bytes_in_use == 0);
}

TEST_CASE("host data: the page of a process that died before it was adopted is not kept",
          "[host-data]") {
  auto data = node::HostData::create({}, 64 << 20).value();
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0)
    ::_exit(0);
  REQUIRE(::waitpid(child, nullptr, 0) == child); // reaped: gone
  auto page = data->reserve_page();
  REQUIRE(page.has_value());
  data->adopt(child, page->first);
  CHECK(data->counts().pages == 0);
  CHECK(data->counts().bytes_in_use == 0);
}

namespace {

// A relay that records what the host's data asks of it.
struct RecordingRelay final : node::TopicRelay {
  std::vector<std::string> *log;
  bool refuse = false;
  std::size_t open_now = 0;
  explicit RecordingRelay(std::vector<std::string> *l) : log(l) {}
  tl::expected<void, std::string> open(const node::RelayRoute &route, shm::RingOwner) override {
    if (refuse)
      return tl::unexpected(std::string("refused"));
    log->push_back(fmt::format("open {} {}", route.topic, route.outbound ? "out" : "in"));
    ++open_now;
    return {};
  }
  void close(const std::string &topic, bool outbound) override {
    log->push_back(fmt::format("close {} {}", topic, outbound ? "out" : "in"));
    --open_now;
  }
  std::size_t relays() const override { return open_now; }
};

protocol::component::ConnectRequest relayed_connect(const std::string &direction,
                                                    const std::string &connection) {
  auto r = same_host_connect(direction, direction == "uses" ? "out" : "in");
  r.connection = connection;
  r.relay = true;
  return r;
}

} // namespace

TEST_CASE("host data: a topic's relay opens with its first relayed end of a direction and closes "
          "with the last",
          "[host-data]") {
  auto data = node::HostData::create({}, 64 << 20).value();
  std::vector<std::string> log;
  RecordingRelay *relay = nullptr;
  REQUIRE(
      data->start_relay([&](const shm::Arena &,
                            std::uint64_t doorbell) -> Expected<std::unique_ptr<node::TopicRelay>> {
            CHECK(doorbell != 0);
            auto made = std::make_unique<RecordingRelay>(&log);
            relay = made.get();
            return std::unique_ptr<node::TopicRelay>(std::move(made));
          })
          .has_value());
  const std::string topic = "rsca/d/app/c1";
  // Two publishers and a subscriber of a channel on this host, and one that is not relayed.
  REQUIRE(data->connect(100, "a", relayed_connect("uses", "p1")).has_value());
  REQUIRE(data->connect(101, "b", relayed_connect("uses", "p2")).has_value());
  REQUIRE(data->connect(102, "c", relayed_connect("provides", "s1")).has_value());
  REQUIRE(data->connect(103, "d", same_host_connect("provides", "in")).has_value());
  for (auto [pid, target, port, connection] : {std::tuple{100, "a", "out", "p1"},
                                               {101, "b", "out", "p2"},
                                               {102, "c", "in", "s1"},
                                               {103, "d", "in", "c1"}})
    data->connected(pid, target, port, connection, true);
  CHECK(log == std::vector<std::string>{"open " + topic + " out", "open " + topic + " in"});
  CHECK(data->counts().relays == 2);
  data->disconnect(100, "a", "out", "p1");
  CHECK(log.size() == 2); // p2 still publishes
  data->forget(101);      // its process ended
  data->disconnect(102, "c", "in", "s1");
  CHECK(log == std::vector<std::string>{"open " + topic + " out", "open " + topic + " in",
                                        "close " + topic + " out", "close " + topic + " in"});
  CHECK(data->counts().relays == 0);
  CHECK(data->counts().rings == 1); // the unrelayed reader's
  // A relay that cannot open refuses the connect, and nothing is held for it.
  relay->refuse = true;
  const auto refused = data->connect(104, "e", relayed_connect("uses", "p3"));
  REQUIRE_FALSE(refused.has_value());
  CHECK(refused.error() == "refused");
  CHECK(data->counts().ends == 1);
  data->disconnect(103, "d", "in", "c1");
  CHECK(data->counts().rings == 0);
}

TEST_CASE("host data: without a relay, a relayed connect is refused", "[host-data]") {
  auto data = node::HostData::create({}, 64 << 20).value();
  const auto refused = data->connect(100, "a", relayed_connect("uses", "p1"));
  REQUIRE_FALSE(refused.has_value());
  CHECK(refused.error() == "this node relays no data to other hosts");
  CHECK(data->counts().rings == 0);
  CHECK(data->counts().ends == 0);
}

TEST_CASE("host data: rings are made as the node was told, limits no ring can have are refused",
          "[host-data]") {
  CHECK_FALSE(node::HostData::create({3000, 64}, 64 << 20).has_value()); // not a power of two
  CHECK_FALSE(node::HostData::create({1U << 30U, 64}, 64 << 20).has_value());
  CHECK_FALSE(node::HostData::create({1U << 16U, 8}, 64 << 20).has_value());
  auto data = node::HostData::create({1U << 20U, 64}, 64 << 20).value();
  const auto writer = data->connect(100, "a", same_host_connect("uses", "out"));
  REQUIRE(writer.has_value());
  auto arena = shm::Arena::map(process::Fd(::dup(data->arena_fd())));
  REQUIRE(arena.has_value());
  auto view = shm::detail::RingView::open(*arena, writer->offset);
  REQUIRE(view.has_value());
  CHECK(view->data_bytes == (1U << 20U)); // a sample of up to 512 KiB goes through
  CHECK(view->records == 64);
  data->disconnect(100, "a", "out", "c1");
}

TEST_CASE("shm: ring limits are checked before a ring is made", "[host-data]") {
  CHECK_FALSE(shm::check({}).has_value()); // the default
  CHECK_FALSE(shm::check({4096, 16}).has_value());
  CHECK(shm::check({4096, 15}).has_value());
  CHECK(shm::check({2048, 16}).has_value());
  CHECK(shm::check({1U << 29U, 16}).has_value());
  CHECK(shm::check({4096, 1U << 21U}).has_value());
}
