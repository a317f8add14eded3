// The QoS of a connection proven end to end on each transport that honours it (issue 38): the
// ring of one node, the relay between two nodes, a TCP stream and direct DDS, with real daemons
// and components (QosSource's producer, QosSink's consumer, which checks the order of the
// sequence numbers it receives). Each check reads what the consumer received and what the live
// ends apply (their "qos" in `rsca ls connections`), never the domain's record of the request.
// What a transport cannot honour (profile/connection_qos.hpp) is refused with the reason.
#include <signal.h>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "qos_checks.hpp"

using namespace rsca::test;
using namespace std::chrono_literals;

namespace {

// Both live ends of connection "c" apply `key` of their QoS as `value`.
template <typename T>
void both_ends_apply(QosPair &pair, const char *key, const T &value) {
  const Json c = pair.connection();
  INFO(c.dump());
  REQUIRE_FALSE(c.is_null());
  for (const char *end : {"uses_state", "provides_state"}) {
    INFO(end);
    REQUIRE(c.at(end).contains("qos"));
    CHECK(c.at(end).at("qos").at(key) == value);
  }
}

} // namespace

TEST_CASE("a reliable connection delivers every sample once and in order on every transport",
          "[integration][qos]") {
  const Way way = GENERATE(kRing, kRelay, kTcp, kDirect);
  INFO(way.name);
  QosPair pair(way, {"reliability=reliable", "history=keeplast", "depth=1000"});
  both_ends_apply(pair, "reliability", "reliable");
  REQUIRE(TestDomain::wait_for([&] { return pair.consumer("received") >= 1000; }, 30s));
  REQUIRE(pair.domain.call("app.stop", Json{{"app", "QosSource"}}).has_value());
  const long last = pair.producer("last_sequence");
  // The last sample written arrives too, and from the first received to it none is missing,
  // none came twice, none out of order.
  CHECK(TestDomain::wait_for([&] { return pair.consumer("last_sequence") == last; }));
  CHECK(pair.consumer("sequence_gaps") == 0);
  CHECK(pair.consumer("sequence_repeats") == 0);
  CHECK(pair.consumer("received") >= 1000);
  pair.release();
  pair.domain.require_clean(pair.pids);
}

// The reader's component stopped (`app.stop`), its process and transport running on: what
// arrives meanwhile is kept by the connection's history, the newest `depth`, and delivered at
// its start, the same on every transport. Freezing the whole process (SIGSTOP) is not this: its
// transport's receive path freezes too, and what its sockets kept arrives once it resumes.
TEST_CASE("a keep-last reader whose component is stopped gets, once started, at most depth of "
          "the samples written meanwhile, the newest, on every transport",
          "[integration][qos][keep-last]") {
  constexpr long kDepth = 5;
  const Way way = GENERATE(kRing, kRelay, kTcp, kDirect);
  INFO(way.name);
  QosPair pair(way, {"reliability=reliable", "history=keeplast", "depth=5"});
  {
    const Json c = pair.connection();
    INFO(c.dump());
    CHECK(c.at("provides_state").at("qos").at("history") == "keeplast");
    CHECK(c.at("provides_state").at("qos").at("depth") == kDepth);
  }
  REQUIRE(pair.domain.call("app.stop", Json{{"app", "QosSink"}}).has_value());
  const long before = pair.producer("last_sequence");
  REQUIRE(
      TestDomain::wait_for([&] { return pair.producer("last_sequence") >= before + 20 * kDepth; }));
  REQUIRE(pair.domain.call("app.stop", Json{{"app", "QosSource"}}).has_value());
  const long last = pair.producer("last_sequence");
  REQUIRE(pair.domain.call("app.start", Json{{"app", "QosSink"}}).has_value());

  // The consumer counts from its start: what it got are the newest, none missing up to the last.
  CHECK(TestDomain::wait_for([&] { return pair.consumer("last_sequence") == last; }));
  const long got = pair.consumer("received");
  INFO("written while stopped " << last - before << ", received at the start " << got);
  CHECK(got >= 1);
  CHECK(got <= kDepth);
  CHECK(pair.consumer("sequence_gaps") == 0);
  CHECK(pair.consumer("sequence_repeats") == 0);
  CHECK(pair.consumer("last_sequence") == last);
  pair.release();
  pair.domain.require_clean(pair.pids);
}

// What arrives for a stopped reader is kept untaken; it still ends each deadline period, as DDS
// counts arrivals rather than takes, on the transports whose reader counts its own misses.
TEST_CASE("a stopped keep-last reader misses no deadline while its writer writes",
          "[integration][qos][keep-last]") {
  const Way way = GENERATE(kRing, kTcp);
  INFO(way.name);
  QosPair pair(way, {"deadline=100ms"});
  REQUIRE(pair.domain.call("app.stop", Json{{"app", "QosSink"}}).has_value());
  // Five periods of 500 Hz samples, none of them taken.
  const long before = pair.producer("last_sequence");
  REQUIRE(TestDomain::wait_for([&] { return pair.producer("last_sequence") >= before + 250; }));
  CHECK(end_value(pair.domain, "c", "provides_state", "deadline_missed") == 0);
  pair.release();
  pair.domain.require_clean(pair.pids);
}

TEST_CASE("a deadline is met with no miss, then missed once the writer stops, through the relay "
          "between two nodes",
          "[integration][qos]") {
  QosPair pair(kRelay, {"deadline=100ms"});
  both_ends_apply(pair, "deadline_ns", 100'000'000);
  // 500 Hz against 100 ms: a second of samples, ten periods, none missed at either end.
  const long from = pair.consumer("received");
  REQUIRE(TestDomain::wait_for([&] { return pair.consumer("received") > from + 500; }));
  {
    const Json c = pair.connection();
    INFO(c.dump());
    CHECK(c.at("provides_state").at("relayed") == true);
    CHECK(c.at("uses_state").at("deadline_missed") == 0);
    CHECK(c.at("provides_state").at("deadline_missed") == 0);
  }
  REQUIRE(pair.domain.call("app.stop", Json{{"app", "QosSource"}}).has_value());
  CHECK(TestDomain::wait_for(
      [&] { return end_value(pair.domain, "c", "provides_state", "deadline_missed") >= 3; }));
  const long missed = end_value(pair.domain, "c", "provides_state", "deadline_missed");
  CHECK(TestDomain::wait_for(
      [&] { return end_value(pair.domain, "c", "provides_state", "deadline_missed") > missed; }));
  CHECK(end_value(pair.domain, "c", "uses_state", "deadline_missed") >= 3);
  pair.release();
  pair.domain.require_clean(pair.pids);
}

TEST_CASE("a writer frozen past its liveliness lease is reported lost by the reader's end, and "
          "delivers again once resumed",
          "[integration][qos]") {
  const Way way = GENERATE(kRing, kRelay, kDirect);
  INFO(way.name);
  QosPair pair(way, {"liveliness=automatic", "lease=300ms"});
  both_ends_apply(pair, "lease_ns", 300'000'000);
  both_ends_apply(pair, "liveliness", "automatic");
  FrozenProcess frozen(pair.producer_pid());
  const Json problem = connection_problem(pair.domain, "liveliness lost");
  frozen.resume();
  INFO(problem.dump());
  REQUIRE_FALSE(problem.is_null());
  CHECK(problem.value("application", "") == "QosSink");
  CHECK(problem.value("component", "") == "Consumer_1");
  CHECK(problem.value("count", 0) > 0);
  const long received = pair.consumer("received");
  CHECK(TestDomain::wait_for([&] { return pair.consumer("received") > received + 50; }));
  pair.release();
  pair.domain.require_clean(pair.pids);
}

TEST_CASE("rsca connect refuses every QoS a named transport cannot honour, with the reason, and "
          "direct DDS takes them all",
          "[integration][qos]") {
  TestDomain domain(1);
  struct Case {
    const char *transport;
    const char *qos;
    const char *says;
  };
  const std::vector<Case> cases{
      {"node", "ownership=exclusive",
       R"(transport="node" does not honour ownership="exclusive" (it delivers every writer))"},
      {"node", "durability=transient",
       R"(transport="node" does not honour durability="transient" (its history goes with the )"
       R"(writer's node))"},
      {"node", "history=keepall",
       R"(transport="node" does not honour reliability="reliable" with history="keepall")"},
      {"tcp", "ownership=exclusive",
       R"(transport="tcp" does not honour ownership="exclusive" (it delivers every writer))"},
      {"tcp", "durability=transientlocal",
       R"(transport="tcp" does not honour durability="transientlocal" (it keeps nothing for a )"
       R"(reader that joins later))"},
      {"tcp", "history=keepall",
       R"(transport="tcp" does not honour reliability="reliable" with history="keepall")"},
      {"tcp", "lease=300ms", R"(transport="tcp" carries no liveliness lease)"},
  };
  for (const auto &c : cases) {
    const std::string id = fmt::format("refused_{}", &c - cases.data());
    auto [rc, out] =
        domain.cli({"connect", "a/Producer_1.samples_out", "b/Consumer_1.samples_in", "--id", id,
                    "--qos", c.qos, "--qos", std::string("transport=") + c.transport});
    INFO(c.transport << " " << c.qos << ": " << out);
    CHECK(rc == 1);
    CHECK_THAT(out, Catch::Contains(c.says));
    CHECK(listed_connection(domain, id).is_null());
  }
  std::vector<std::string> all{
      "connect", "a/Producer_1.samples_out", "b/Consumer_1.samples_in", "--id", "direct",
      "--qos",   "transport=direct"};
  for (const char *qos :
       {"ownership=exclusive", "durability=transient", "history=keepall", "lease=300ms"})
    all.insert(all.end(), {"--qos", qos});
  auto [rc, out] = domain.cli(all);
  INFO(out);
  REQUIRE(rc == 0);
  const Json listed = listed_connection(domain, "direct");
  REQUIRE_FALSE(listed.is_null());
  CHECK(listed.at("qos").at("ownership") == "exclusive");
  REQUIRE(domain.cli({"disconnect", "direct"}).first == 0);
  domain.require_clean({});
}
