// Looking at a live domain's data (issue 39 item 9): the events of an application's start and
// stop and no false deadline miss after a stop, long property values summarised by rsca query,
// rsca top -w refreshing.
#include <catch2/catch.hpp>

#include <sstream>

#include "domain_fixture.hpp"
#include "wait_for.hpp"

using namespace rsca::test;

namespace {

// The domain's recent events as `rsca --json events` prints them, in order.
std::vector<Json> dataview_events(TestDomain &domain) {
  auto [rc, out] = domain.cli({"--json", "events", "--wait-ms", "500"});
  INFO(out);
  REQUIRE(rc == 0);
  std::vector<Json> events;
  std::istringstream lines(out);
  for (std::string line; std::getline(lines, line);)
    events.push_back(Json::parse(line));
  return events;
}

// The index of the first event of `kind` for application `app` at or after `from`; -1: none.
long dataview_find(const std::vector<Json> &events, const std::string &kind, const std::string &app,
                   std::size_t from = 0) {
  for (std::size_t i = from; i < events.size(); ++i)
    if (events[i].at("kind") == kind && events[i].at("details").value("application", "") == app)
      return static_cast<long>(i);
  return -1;
}

// The lines of `text` that start with `prefix`.
std::vector<std::string> dataview_lines(const std::string &text, const std::string &prefix) {
  std::vector<std::string> out;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);)
    if (line.rfind(prefix, 0) == 0)
      out.push_back(line);
  return out;
}

} // namespace

TEST_CASE("rsca events shows an application's start and stop, and no deadline missed after the "
          "stop",
          "[integration][events][dataview]") {
  // ProducerConsumer's connection asks for a sample every 100 ms; stopped, the producer writes
  // none, which is no problem of the connection.
  const std::string name =
      GENERATE(as<std::string>{}, "ProducerConsumer", "ProducerConsumerHosted");
  INFO(name);
  constexpr auto kDeadline = std::chrono::milliseconds(100);
  // A component looks for problems every 100 ms and reports them once a second at most: a miss
  // counted within the window is reported within it.
  constexpr auto kWindow = 3 * kDeadline + std::chrono::milliseconds(100) + std::chrono::seconds(1);
  TestDomain domain;
  const Json app = domain.launch_shipped(name);
  REQUIRE(received(domain, name) >= 0);
  auto [stop_rc, stop_out] = domain.cli({"stop", name});
  INFO(stop_out);
  REQUIRE(stop_rc == 0);
  std::vector<Json> events;
  REQUIRE(TestDomain::wait_for([&] {
    events = dataview_events(domain);
    return dataview_find(events, "application.stopped", name) >= 0;
  }));
  // The observation window, on the steady clock: three deadline periods and a report's delay.
  const auto window_end = std::chrono::steady_clock::now() + kWindow;
  wait_until([&] { return std::chrono::steady_clock::now() >= window_end; }, 2 * kWindow);
  REQUIRE(std::chrono::steady_clock::now() >= window_end);
  events = dataview_events(domain);
  const long created = dataview_find(events, "application.created", name);
  const long stopped = dataview_find(events, "application.stopped", name);
  REQUIRE(created >= 0);
  REQUIRE(stopped > created);
  CHECK(events[static_cast<std::size_t>(created)].at("details").at("started") == true);
  for (std::size_t i = static_cast<std::size_t>(stopped); i < events.size(); ++i) {
    INFO(events[i].dump());
    CHECK_FALSE(events[i].at("kind") == "connection.problem");
  }
  // Started again, it is told too, and the stop's gap is no problem either.
  REQUIRE(domain.cli({"start", name}).first == 0);
  REQUIRE(TestDomain::wait_for([&] {
    events = dataview_events(domain);
    return dataview_find(events, "application.started", name) >= 0;
  }));
  const long started = dataview_find(events, "application.started", name);
  CHECK(started > dataview_find(events, "application.stopped", name));
  const long before = received(domain, name);
  REQUIRE(TestDomain::wait_for([&] { return received(domain, name) > before + 5; }));
  events = dataview_events(domain);
  for (std::size_t i = static_cast<std::size_t>(started); i < events.size(); ++i) {
    INFO(events[i].dump());
    CHECK_FALSE(events[i].at("kind") == "connection.problem");
  }
  REQUIRE(domain.call("app.release", Json{{"app", name}}).has_value());
  domain.require_clean(pids_of(app));
}

TEST_CASE("rsca query summarises a long sequence; --full and --json print it whole",
          "[integration][dataview]") {
  TestDomain domain({TestDomain::shipped_nodes(1)[0],
                     kSource / "profiles/dev/nodes/robot/DeviceManager.dcd.xml"});
  // The Robot's trace grows as its world runs: a point every 10 ms.
  std::size_t points = 0;
  REQUIRE(TestDomain::wait_for([&] {
    auto q = domain.call("app.query", Json{{"device", "robot:Robot_1"}, {"ids", {"trace_time"}}});
    points = q ? q->at("properties").at("trace_time").size() : 0;
    return points > 20;
  }));
  auto [rc, out] = domain.cli({"query", "robot:Robot_1", "trace_time"});
  INFO(out);
  REQUIRE(rc == 0);
  const auto summary = dataview_lines(out, "trace_time = [");
  REQUIRE(summary.size() == 1);
  CHECK_THAT(
      summary[0],
      Catch::Matches(R"(trace_time = \[[-0-9.e]+, [-0-9.e]+, [-0-9.e]+, … [0-9]+ values\])"));
  // Whole: every number, as many as the trace had then at least.
  auto [full_rc, full] = domain.cli({"query", "robot:Robot_1", "trace_time", "--full"});
  REQUIRE(full_rc == 0);
  const auto whole = dataview_lines(full, "trace_time = [");
  REQUIRE(whole.size() == 1);
  CHECK(static_cast<std::size_t>(std::count(whole[0].begin(), whole[0].end(), ',')) + 1 >= points);
  CHECK(whole[0].find("…") == std::string::npos);
  auto [json_rc, json] = domain.cli({"--json", "query", "robot:Robot_1", "trace_time"});
  INFO(json);
  REQUIRE(json_rc == 0);
  CHECK(Json::parse(json).at("properties").at("trace_time").size() >= points);
}

TEST_CASE("rsca top -n 2 prints two tables, one after the other when not on a terminal",
          "[integration][top][dataview]") {
  TestDomain domain;
  const Json app = domain.launch_shipped("ProducerConsumer");
  auto [rc, out] = domain.cli({"top", "-w", "--interval", "200ms", "-n", "2"});
  INFO(out);
  REQUIRE(rc == 0);
  CHECK(dataview_lines(out, "HOST/NODE").size() == 2);
  CHECK(dataview_lines(out, "\x1b[H").empty()); // a pipe is not redrawn
  auto [json_rc, json] = domain.cli({"--json", "top", "ProducerConsumer", "-n", "2"});
  INFO(json);
  REQUIRE(json_rc == 0);
  std::istringstream lines(json);
  int tables = 0;
  for (std::string line; std::getline(lines, line); ++tables)
    CHECK(Json::parse(line).at("processes").size() == 2);
  CHECK(tables == 2);
  auto [bad_rc, bad] = domain.cli({"top", "-w", "--interval", "soon"});
  INFO(bad);
  CHECK(bad_rc == 2);
  CHECK_THAT(bad, Catch::Contains("--interval soon"));
  REQUIRE(domain.call("app.release", Json{{"app", "ProducerConsumer"}}).has_value());
  domain.require_clean(pids_of(app));
}
