// Looking at a live domain's data (issue 39 item 9): the events of an application's start and
// stop and no false deadline miss after a stop, long property values summarised by rsca query,
// rsca top -w refreshing.
#include <catch2/catch.hpp>

#include <csignal>
#include <sstream>

#include "child_process.hpp"
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

TEST_CASE("rsca query summarises a long sequence, --full and --json print it whole",
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

namespace {

// The sequence numbers of `rsca --json echo` lines.
std::vector<long> dataview_sequences(const std::string &out) {
  std::vector<long> sequences;
  std::istringstream lines(out);
  for (std::string line; std::getline(lines, line);)
    sequences.push_back(Json::parse(line).at("sequence").get<long>());
  return sequences;
}

long dataview_property(TestDomain &domain, const std::string &app, const std::string &component,
                       const std::string &id) {
  auto q = domain.call("app.query", Json{{"app", app}, {"component", component}, {"ids", {id}}});
  REQUIRE(q.has_value());
  return q->at("properties").at(id).get<long>();
}

} // namespace

TEST_CASE("rsca echo prints the producer's samples as they flow and rsca hz their rate, without "
          "disturbing the connection",
          "[integration][echo][dataview]") {
  // Through the node's ring (ProducerConsumer, one node) and direct DDS (DirectPair).
  const std::string name = GENERATE(as<std::string>{}, "ProducerConsumer", "DirectPair");
  INFO(name);
  TestDomain domain;
  Json app;
  if (name == "ProducerConsumer") {
    app = domain.launch_shipped(name);
  } else {
    domain.install(name);
    auto [rc, out] = domain.cli({"launch", name});
    INFO(out);
    REQUIRE(rc == 0);
    app = *domain.call("app.show", Json{{"app", name}});
  }
  REQUIRE(TestDomain::wait_for([&] { return received(domain, name) > 5; }));
  const long before = dataview_property(domain, name, "Producer_1", "last_sequence");
  auto [rc, out] = domain.cli({"--json", "echo", name + "/Producer_1.samples_out", "-n", "5"});
  INFO(out);
  REQUIRE(rc == 0);
  const long after = dataview_property(domain, name, "Producer_1", "last_sequence");
  const auto sequences = dataview_sequences(out);
  REQUIRE(sequences.size() == 5);
  for (std::size_t i = 0; i < sequences.size(); ++i) {
    CHECK(sequences[i] >= before); // the producer's, as it wrote them meanwhile
    CHECK(sequences[i] <= after);
    if (i > 0)
      CHECK(sequences[i] > sequences[i - 1]);
  }
  // The port named from the reader's side, in text: summarised samples.
  auto [text_rc, text] = domain.cli({"echo", name + ".samples_in", "-n", "1"});
  INFO(text);
  REQUIRE(text_rc == 0);
  CHECK_THAT(text, Catch::Contains("\"sequence\": "));

  // A viewer attached for a while: the consumer keeps receiving, and after it has gone.
  const long received_before = received(domain, name);
  auto [hz_rc, hz] =
      domain.cli({"--json", "hz", name + "/Producer_1.samples_out", "-w", "2s", "-n", "1"});
  INFO(hz);
  REQUIRE(hz_rc == 0);
  const Json rate = Json::parse(hz);
  // The producer writes at 50 Hz (ProducerConsumer) or 100 Hz (DirectPair's default): a broad
  // functional range, not a speed goal.
  CHECK(rate.at("rate_hz").get<double>() > 10);
  CHECK(rate.at("rate_hz").get<double>() < 200);
  CHECK(rate.at("gap_min_ms").get<double>() > 0);
  CHECK(rate.at("gap_max_ms").get<double>() >= rate.at("gap_mean_ms").get<double>());
  const long received_during = received(domain, name);
  CHECK(received_during > received_before + 10);
  REQUIRE(TestDomain::wait_for([&] { return received(domain, name) > received_during + 10; }));

  // A viewer that stops reading (frozen) holds nothing back either, nor one that dies.
  const fs::path viewer_out = domain.run_dir() / "viewer.out";
  ChildProcess viewer((kBin / "rsca").string(), {"echo", name + "/Producer_1.samples_out"},
                      domain.env(), viewer_out);
  REQUIRE(TestDomain::wait_for(
      [&] { return read_file(viewer_out).find("\"sequence\": ") != std::string::npos; }));
  viewer.signal(SIGSTOP);
  const long received_frozen = received(domain, name);
  CHECK(TestDomain::wait_for([&] { return received(domain, name) > received_frozen + 100; }));
  viewer.signal(SIGKILL);
  REQUIRE(viewer.wait_exit(5s).has_value());
  const long received_killed = received(domain, name);
  CHECK(TestDomain::wait_for([&] { return received(domain, name) > received_killed + 20; }));

  // Stopped, nothing flows: the viewer says so within its wait, and fails.
  REQUIRE(domain.cli({"stop", name}).first == 0);
  auto [quiet_rc, quiet] = domain.cli({"echo", name + "/Producer_1.samples_out", "--wait", "1s"});
  INFO(quiet);
  CHECK(quiet_rc == 6);
  CHECK_THAT(quiet, Catch::Contains("no sample on connection samples for 1s"));
  auto [bad_rc, bad] = domain.cli({"echo", name + "/Producer_1.no_such_port"});
  CHECK(bad_rc == 3);
  CHECK_THAT(bad, Catch::Contains("has no data connection of port Producer_1.no_such_port"));
  REQUIRE(domain.call("app.release", Json{{"app", name}}).has_value());
  domain.require_clean(pids_of(app));
}
