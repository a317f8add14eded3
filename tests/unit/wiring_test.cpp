// The wiring service against a fake control plane: the order of its calls, what each end is
// asked, and what it reports as made when a call fails.
#include <catch2/catch.hpp>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include "control/caller.hpp"
#include "domain/wiring.hpp"
#include "protocol/component_ops.hpp"

namespace {

using rsca::domain::Wire;
using rsca::domain::WireEnd;
using rsca::domain::Wiring;
using Json = rsca::control::Json;

// Answers every call as a component would, except to `fail_at` (an address) or with fewer
// matched peers than awaited when `match` is false; records each batch of calls.
class FakeComponents final : public rsca::control::Caller {
public:
  std::string fail_at;
  bool match = true;
  std::vector<std::vector<rsca::control::Call>> batches;

  std::vector<rsca::control::CallResult<Json>>
  call_all(const std::vector<rsca::control::Call> &calls, std::chrono::milliseconds) override {
    batches.push_back(calls);
    std::vector<rsca::control::CallResult<Json>> out;
    for (const auto &c : calls) {
      if (c.target == fail_at) {
        out.emplace_back(tl::unexpect,
                         rsca::protocol::CallError{rsca::protocol::Status::Failed, "refused"});
        continue;
      }
      out.emplace_back(tl::in_place, answer(c));
    }
    return out;
  }
  void route(const std::string &, const std::string &) override {}
  void prepare(const std::string &) override {}
  void forget(const std::string &) override {}

  // The requests of operation `Op` made, decoded, in order.
  template <typename Op>
  std::vector<typename Op::Request> requests() const {
    std::vector<typename Op::Request> out;
    for (const auto &batch : batches)
      for (const auto &c : batch)
        if (c.operation == Op::name)
          out.push_back(rsca::protocol::decode<typename Op::Request>(c.body).value());
    return out;
  }

private:
  Json answer(const rsca::control::Call &c) const {
    if (c.operation != rsca::protocol::component::AwaitMatched::name)
      return Json::object();
    auto request =
        rsca::protocol::decode<rsca::protocol::component::AwaitMatchedRequest>(c.body).value();
    rsca::protocol::component::AwaitMatchedReply reply{match, request.connections};
    for (auto &awaited : reply.connections)
      awaited.matched = match ? awaited.peers : 0;
    return rsca::protocol::encode(reply);
  }
};

WireEnd end_at(std::string address, std::string port, std::string host = "",
               std::string node = "") {
  return {address, port, "c1", std::move(host), 1, address + "." + port, std::move(node)};
}

Wire topic_wire(WireEnd uses, WireEnd provides) {
  return {uses, provides, "rsca/test/c1", "", "", "IDL:T:1.0", Json::object(), "range < 2"};
}

} // namespace

TEST_CASE("wiring: readers first, then writers, then one wait per address", "[wiring]") {
  FakeComponents fake;
  std::vector<WireEnd> made;
  auto wired = Wiring(fake, std::chrono::milliseconds(100))
                   .connect({topic_wire(end_at("a", "out"), end_at("b", "in"))}, made);
  REQUIRE(wired.has_value());
  REQUIRE(fake.batches.size() == 3);
  CHECK(fake.batches[0].at(0).target == "b"); // the reader
  CHECK(fake.batches[1].at(0).target == "a"); // the writer
  CHECK(fake.batches[2].size() == 2);         // a wait at each end
  CHECK(fake.batches[2].at(0).operation == rsca::protocol::component::AwaitMatched::name);
  CHECK(made.size() == 2);
  const auto connects = fake.requests<rsca::protocol::component::Connect>();
  REQUIRE(connects.size() == 2);
  CHECK(connects[0].direction == "provides");
  CHECK(connects[0].filter == "range < 2"); // the reader filters
  CHECK(connects[1].filter == "");          // the writer does not
  CHECK(connects[0].local == false);
}

TEST_CASE("wiring: both ends in one component host take the in-host path", "[wiring]") {
  FakeComponents fake;
  std::vector<WireEnd> made;
  REQUIRE(Wiring(fake, std::chrono::milliseconds(100))
              .connect({topic_wire(end_at("a", "out", "host1"), end_at("b", "in", "host1"))}, made)
              .has_value());
  for (const auto &r : fake.requests<rsca::protocol::component::Connect>())
    CHECK(r.local == true);
  fake.batches.clear();
  REQUIRE(Wiring(fake, std::chrono::milliseconds(100))
              .connect({topic_wire(end_at("a", "out", "host1"), end_at("b", "in", "host2"))}, made)
              .has_value());
  for (const auto &r : fake.requests<rsca::protocol::component::Connect>())
    CHECK(r.local == false);
}

TEST_CASE("wiring: a process a node relays for goes through that node, across nodes, relayed",
          "[wiring]") {
  using rsca::protocol::component::Connect;
  auto wire = [](std::string uses_host, std::string uses_node, std::string provides_host,
                 std::string provides_node) {
    FakeComponents fake;
    std::vector<WireEnd> made;
    REQUIRE(Wiring(fake, std::chrono::milliseconds(100))
                .connect({topic_wire(end_at("a", "out", uses_host, uses_node),
                                     end_at("b", "in", provides_host, provides_node))},
                         made)
                .has_value());
    return fake.requests<Connect>();
  };
  for (const auto &r : wire("", "node1", "", "node1")) { // one node: its ring only
    CHECK(r.shared_memory == true);
    CHECK(r.relay == false);
    CHECK(r.local == false);
  }
  for (const auto &r : wire("", "node1", "", "node2")) { // two nodes: each node's ring, relayed
    CHECK(r.shared_memory == true);
    CHECK(r.relay == true);
  }
  // A device of the node or an unrelayed process is on DDS itself; the relayed end reaches it
  // through its node's relay.
  const auto to_device = wire("", "node1", "", "");
  REQUIRE(to_device.size() == 2);
  for (const auto &r : to_device)
    CHECK(r.shared_memory.has_value() == (r.port == "out"));
  for (const auto &r : to_device)
    if (r.port == "out")
      CHECK(r.relay == true);
  {
    FakeComponents fake;
    std::vector<WireEnd> made;
    Wire direct = topic_wire(end_at("a", "out", "", "node1"), end_at("b", "in", "", "node1"));
    direct.qos = Json{{"transport", "direct"}}; // asked for DDS from the processes
    REQUIRE(Wiring(fake, std::chrono::milliseconds(100)).connect({direct}, made).has_value());
    for (const auto &r : fake.requests<Connect>())
      CHECK_FALSE(r.shared_memory.has_value());
  }
  for (const auto &r : wire("host1", "node1", "host1", "node1")) { // one process: in-host
    CHECK(r.local == true);
    CHECK_FALSE(r.shared_memory.has_value());
  }
}

TEST_CASE("wiring: a failed writer leaves the reader made, for its caller to undo", "[wiring]") {
  FakeComponents fake;
  fake.fail_at = "a";
  std::vector<WireEnd> made;
  Wiring wiring(fake, std::chrono::milliseconds(100));
  auto wired = wiring.connect({topic_wire(end_at("a", "out"), end_at("b", "in"))}, made);
  REQUIRE_FALSE(wired.has_value());
  CHECK(wired.error().message == "a.out: refused");
  REQUIRE(made.size() == 1);
  CHECK(made[0].address == "b");
  CHECK(
      fake.requests<rsca::protocol::component::AwaitMatched>().empty()); // no wait after a failure
  fake.fail_at.clear();
  CHECK(wiring.disconnect(made).empty());
  const auto disconnects = fake.requests<rsca::protocol::component::Disconnect>();
  REQUIRE(disconnects.size() == 1);
  CHECK(disconnects[0].connection == "c1");
  CHECK(disconnects[0].port == "in");
}

TEST_CASE("wiring: ends that do not match in time fail the connect, naming them", "[wiring]") {
  FakeComponents fake;
  fake.match = false;
  std::vector<WireEnd> made;
  auto wired = Wiring(fake, std::chrono::milliseconds(100))
                   .connect({topic_wire(end_at("a", "out"), end_at("b", "in"))}, made);
  REQUIRE_FALSE(wired.has_value());
  CHECK(wired.error().status == rsca::protocol::Status::Unavailable);
  CHECK_THAT(wired.error().message, Catch::Contains("c1 on port out: 0 of 1 peers matched"));
  CHECK(made.size() == 2);
}

TEST_CASE("wiring: an interface connection calls its target, with nothing to await", "[wiring]") {
  FakeComponents fake;
  Wire w;
  w.uses = end_at("a", "ctl");
  w.interface_target = "target-address";
  w.repid = "IDL:Ctl:1.0";
  std::vector<WireEnd> made;
  REQUIRE(Wiring(fake, std::chrono::milliseconds(100)).connect({w}, made).has_value());
  const auto connects = fake.requests<rsca::protocol::component::Connect>();
  REQUIRE(connects.size() == 1);
  CHECK(connects[0].target == "target-address");
  CHECK_FALSE(connects[0].topic.has_value());
  CHECK(fake.requests<rsca::protocol::component::AwaitMatched>().empty());
}

TEST_CASE("wiring: a failed disconnect is reported by the end's name", "[wiring]") {
  FakeComponents fake;
  fake.fail_at = "b";
  const auto failed = Wiring(fake, std::chrono::milliseconds(100))
                          .disconnect({end_at("a", "out"), end_at("b", "in")});
  CHECK(failed == std::vector<std::string>{"b.in: refused"});
}
