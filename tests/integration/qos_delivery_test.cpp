// The QoS a connection asks for, checked on what its reader receives with real daemons and
// components (issue 37, defects 3 and 13): a transient-local late joiner gets the history through
// a node's ring, through the relay between two nodes and on direct DDS; exclusive ownership, which
// the rings cannot honour, travels on direct DDS and delivers only the strongest writer, or is
// refused with the reason when a transport that cannot honour it is named; a deadline is applied
// by each end of each transport and its misses counted.
#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "qos_checks.hpp"

using namespace rsca::test;
using namespace std::chrono_literals;

namespace {

// DurableTicks<suffix> publishes, is stopped, and LateTicks<suffix> joins its channel afterwards:
// the late consumer receives exactly the last 5 ticks (its depth), though nothing is written any
// more. `launch_late` holds the CLI options of the second launch.
void late_joiner_gets_history(TestDomain &domain, const std::string &suffix,
                              const std::vector<std::string> &launch_late, bool other_node) {
  const std::string source = "DurableTicks" + suffix, late = "LateTicks" + suffix;
  domain.install(source);
  REQUIRE(domain.cli({"launch", source}).first == 0);
  REQUIRE(TestDomain::wait_for(
      [&] { return end_value(domain, "publish", "uses_state", "samples") > 20; }));
  REQUIRE(domain.call("app.stop", Json{{"app", source}}).has_value());
  const long written = end_value(domain, "publish", "uses_state", "samples");

  domain.install(late);
  std::vector<std::string> args{"launch", late};
  args.insert(args.end(), launch_late.begin(), launch_late.end());
  auto [rc, out] = domain.cli(args);
  INFO(out);
  REQUIRE(rc == 0);
  if (other_node)
    REQUIRE(node_of(domain, late) != node_of(domain, source));
  CHECK(TestDomain::wait_for(
      [&] { return property(domain, late, "Consumer_1", "events_received") == 5; }));
  // No more than its depth, and nothing new was written meanwhile.
  CHECK(end_value(domain, "late", "provides_state", "samples") == 5);
  CHECK(property(domain, late, "Consumer_1", "events_received") == 5);
  CHECK(end_value(domain, "publish", "uses_state", "samples") == written);

  const auto pids = [&] {
    std::vector<long> all;
    for (const char *app : {source.c_str(), late.c_str()})
      for (long pid : pids_of(domain.call("app.show", Json{{"app", app}}).value()))
        all.push_back(pid);
    return all;
  }();
  REQUIRE(domain.call("app.release", Json{{"app", late}}).has_value());
  REQUIRE(domain.call("app.release", Json{{"app", source}}).has_value());
  domain.require_clean(pids);
}

} // namespace

TEST_CASE("a transient-local late joiner of an event channel gets the last samples through a "
          "node's ring",
          "[integration][qos]") {
  TestDomain domain(1);
  late_joiner_gets_history(domain, "", {}, false);
}

TEST_CASE("a transient-local late joiner of an event channel gets the last samples through the "
          "relays of two nodes",
          "[integration][qos]") {
  TestDomain domain(2);
  late_joiner_gets_history(domain, "", {"--strategy", "spread"}, true);
}

TEST_CASE("a transient-local late joiner of an event channel gets the last samples on direct DDS",
          "[integration][qos]") {
  TestDomain domain(1);
  late_joiner_gets_history(domain, "Direct", {}, false);
}

TEST_CASE("exclusive ownership with no transport named travels on direct DDS and delivers only "
          "the strongest writer",
          "[integration][qos]") {
  TestDomain domain(1);
  const auto pids = pids_of(domain.create("Strongest"));
  auto listed = domain.call("connection.list", Json{{"app", "Strongest"}});
  REQUIRE(listed.has_value());
  for (const auto &c : listed->at("connections")) {
    INFO(c.dump());
    CHECK(c.at("qos").at("transport") == "direct");
  }
  // Consumer_2 takes only the weaker writer's ticks: while the stronger one writes, none.
  REQUIRE(TestDomain::wait_for(
      [&] { return property(domain, "Strongest", "Consumer_1", "events_received") > 50; }));
  const long weak_before = end_value(domain, "weak", "uses_state", "samples");
  const long weak_delivered = property(domain, "Strongest", "Consumer_2", "events_received");
  REQUIRE(TestDomain::wait_for(
      [&] { return end_value(domain, "weak", "uses_state", "samples") > weak_before + 50; }));
  CHECK(property(domain, "Strongest", "Consumer_2", "events_received") == weak_delivered);
  // Consumer_1 got the stronger writer's ticks alone, not both writers' (its count read first:
  // the writers go on writing).
  const long all = property(domain, "Strongest", "Consumer_1", "events_received");
  const long strong = end_value(domain, "strong", "uses_state", "samples");
  CHECK(all <= strong + 2); // the weaker writer may own the instance until the stronger writes
  CHECK(all < strong + end_value(domain, "weak", "uses_state", "samples") / 2);
  REQUIRE(domain.call("app.release", Json{{"app", "Strongest"}}).has_value());
  domain.require_clean(pids);
}

TEST_CASE("rsca connect refuses a transport named that cannot honour the QoS, with the reason, "
          "and takes one that can when none is named",
          "[integration][qos]") {
  TestDomain domain(1);
  auto [rc, out] =
      domain.cli({"connect", "a/Producer_1.samples_out", "b/Consumer_1.samples_in", "--id", "owned",
                  "--qos", "ownership=exclusive", "--qos", "transport=node"});
  INFO(out);
  CHECK(rc == 1);
  CHECK_THAT(out, Catch::Contains("transport=\"node\" does not honour ownership=\"exclusive\""));
  CHECK(listed_connection(domain, "owned").is_null());
  auto [krc, kout] =
      domain.cli({"connect", "a/Producer_1.samples_out", "b/Consumer_1.samples_in", "--id",
                  "all_kept", "--qos", "history=keepall", "--qos", "transport=tcp"});
  INFO(kout);
  CHECK(krc == 1);
  CHECK_THAT(kout, Catch::Contains("transport=\"tcp\" does not honour reliability=\"reliable\" "
                                   "with history=\"keepall\""));
  CHECK(listed_connection(domain, "all_kept").is_null());

  auto [arc, aout] = domain.cli({"connect", "a/Producer_1.samples_out", "b/Consumer_1.samples_in",
                                 "--id", "owned", "--qos", "ownership=exclusive"});
  INFO(aout);
  REQUIRE(arc == 0);
  CHECK(listed_connection(domain, "owned").at("qos").at("transport") == "direct");
}

TEST_CASE("rsca connect --qos deadline=100ms: each end of each transport applies it, and counts "
          "the misses once the writer stops",
          "[integration][qos]") {
  TestDomain domain(1);
  const auto sad =
      (kSource / "profiles/dom/waveforms/ProducerConsumer/ProducerConsumer.sad.xml").string();
  REQUIRE(domain.cli({"launch", sad, "--name", "a"}).first == 0);
  REQUIRE(domain.cli({"launch", "ProducerConsumer", "--name", "b"}).first == 0);
  const std::vector<long> pids = [&] {
    auto a = pids_of(domain.call("app.show", Json{{"app", "a"}}).value());
    auto b = pids_of(domain.call("app.show", Json{{"app", "b"}}).value());
    a.insert(a.end(), b.begin(), b.end());
    return a;
  }();
  const std::vector<std::string> transports{"node", "direct", "tcp"};
  for (const auto &t : transports) {
    auto [rc, out] =
        domain.cli({"connect", "a/Producer_1.samples_out", "b/Consumer_1.samples_in", "--id",
                    "deadline_" + t, "--qos", "deadline=100ms", "--qos", "transport=" + t});
    INFO(out);
    REQUIRE(rc == 0);
  }
  for (const auto &t : transports) {
    const std::string id = "deadline_" + t;
    INFO(id);
    CHECK(TestDomain::wait_for([&] { return delivered(domain, id) > 20; }));
    const Json c = listed_connection(domain, id);
    INFO(c.dump());
    CHECK(c.at("qos").at("deadline_ns") == 100'000'000);
    CHECK(c.at("uses_state").at("deadline_ns") == 100'000'000);
    CHECK(c.at("provides_state").at("deadline_ns") == 100'000'000);
    CHECK(c.at("provides_state").at("deadline_missed") == 0); // 100 Hz: met
  }
  REQUIRE(domain.call("app.stop", Json{{"app", "a"}}).has_value());
  for (const auto &t : transports) {
    const std::string id = "deadline_" + t;
    INFO(id);
    CHECK(TestDomain::wait_for(
        [&] { return end_value(domain, id, "provides_state", "deadline_missed") >= 3; }));
    const long missed = end_value(domain, id, "provides_state", "deadline_missed");
    CHECK(TestDomain::wait_for(
        [&] { return end_value(domain, id, "provides_state", "deadline_missed") > missed; }));
  }
  for (const auto &t : transports)
    REQUIRE(domain.cli({"disconnect", "deadline_" + t}).first == 0);
  REQUIRE(domain.call("app.release", Json{{"app", "a"}}).has_value());
  REQUIRE(domain.call("app.release", Json{{"app", "b"}}).has_value());
  domain.require_clean(pids);
}
