// The robot in the loop through a real domain: the robot node's devices (Robot, IRSensor,
// DriveSystem) and StopCrash as a component process on another node, wired by the domain.
#include <algorithm>

#include "domain_fixture.hpp"
#include "sim/drive.hpp"
#include "sim/scenario.hpp"

using namespace rsca::test;
using namespace std::chrono_literals;

namespace {

const fs::path kRobotNode = kSource / "profiles/dev/nodes/robot/DeviceManager.dcd.xml";
const fs::path kRangeStop = kSource / "profiles/dom/waveforms/RangeStop/RangeStop.sad.xml";

Json properties(TestDomain &domain, Json target) {
  auto q = domain.call("app.query", std::move(target));
  REQUIRE(q.has_value());
  return q->at("properties");
}

double robot(TestDomain &domain, const std::string &id) {
  return properties(domain, {{"device", "robot:Robot_1"}, {"ids", {id}}}).at(id).get<double>();
}

Json drive(TestDomain &domain) {
  return properties(domain, {{"device", "robot:DriveSystem_1"}, {"ids", Json::array()}});
}

// Launches RangeStop with StopCrash's speed and threshold, started.
Json launch(TestDomain &domain, double speed, double threshold) {
  auto [rc, out] = domain.cli({"launch", kRangeStop.string(), "--no-start"});
  INFO(out);
  REQUIRE(rc == 0);
  REQUIRE(
      domain
          .call("app.configure", Json{{"app", "RangeStop"},
                                      {"component", "StopCrash_1"},
                                      {"properties", {{"speed", speed}, {"threshold", threshold}}}})
          .has_value());
  REQUIRE(domain.call("app.start", Json{{"app", "RangeStop"}}).has_value());
  auto app = domain.call("app.show", Json{{"app", "RangeStop"}});
  REQUIRE(app.has_value());
  return *app;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

bool at_rest(TestDomain &domain) {
  return std::abs(robot(domain, "speed")) < 1e-3;
}

// Waits for the robot to come to rest after it has moved.
bool rests(TestDomain &domain) {
  return TestDomain::wait_for([&] { return at_rest(domain) && robot(domain, "sim_time") > 1; },
                              60s);
}

struct TracePoint {
  double time, distance_to_wall, speed, commanded;
};
using Trace = std::vector<TracePoint>;

// The Robot's trace once it reaches sim time `until` (it is published every 10 service ticks).
Trace robot_trace(TestDomain &domain, double until) {
  const std::vector<std::string> ids{"trace_time", "trace_distance", "trace_speed",
                                     "trace_command"};
  Json p;
  REQUIRE(TestDomain::wait_for([&] {
    p = properties(domain, {{"device", "robot:Robot_1"}, {"ids", ids}});
    const auto &time = p.at("trace_time");
    return !time.empty() && time.back().get<double>() >= until;
  }));
  Trace trace;
  for (std::size_t i = 0; i < p.at("trace_time").size(); ++i)
    trace.push_back({p.at("trace_time")[i].get<double>(), p.at("trace_distance")[i].get<double>(),
                     p.at("trace_speed")[i].get<double>(), p.at("trace_command")[i].get<double>()});
  return trace;
}

// The index of the first point later than `time` that satisfies `match`.
template <typename Match>
std::optional<std::size_t> first_point_after(const Trace &trace, double time, Match match) {
  for (std::size_t i = 0; i < trace.size(); ++i)
    if (trace[i].time > time && match(trace[i]))
      return i;
  return std::nullopt;
}

} // namespace

TEST_CASE("RangeStop through the domain: StopCrash on node1 stops the robot at the threshold, "
          "within what the physics explains",
          "[integration][robot]") {
  TestDomain domain({TestDomain::shipped_nodes(1)[0], kRobotNode});
  const double speed = 0.3, threshold = 0.6;
  const Json app = launch(domain, speed, threshold);
  CHECK(app.at("components")[0].at("device") == "node1:GPP_1");
  REQUIRE(TestDomain::wait_for([&] { return robot(domain, "speed") > 0.25; }, 20s));
  REQUIRE(rests(domain));
  // The tolerance: at speed for up to a sensor period (20 ms), the slowest sensor-to-command
  // latency the drive measured and a world step before the stop takes effect, then the braking
  // distance; give or take two sigmas of the sensor's noise. The latency is the measured one: a
  // loaded host delays the stop, and the physics must still explain where the robot rests.
  const Json d = drive(domain);
  const auto scenario = rsca::sim::default_scenario();
  const double transport = d.at("latency_max_us").get<double>() * 1e-6;
  const double tolerance = rsca::sim::stop_tolerance_terms(scenario.robot, scenario.friction, speed,
                                                           0.020 + scenario.time_step, transport,
                                                           scenario.sensors.front().noise_sigma)
                               .total();
  const double distance = robot(domain, "distance_to_wall");
  INFO("rested " << distance << " m from the wall; tolerance " << tolerance << " with "
                 << transport * 1e3 << " ms of sensor-to-command latency");
  CHECK(distance < threshold);
  CHECK(distance > threshold - tolerance);
  CHECK(d.at("latency_samples").get<long>() > 50);
  CHECK(d.at("latency_p50_us").get<double>() > 0);
  CHECK(d.at("safety_stops") == 0);
  // The command log a benchmark cuts at rest: every command so far (fewer than its size), in the
  // order they came, the world's time not going back, the largest delay the drive's maximum.
  const auto delays = d.at("command_log_delay_us").get<std::vector<double>>();
  const auto times = d.at("command_log_sim_time").get<std::vector<double>>();
  CHECK(d.at("command_log_first") == 0);
  CHECK(delays.size() == d.at("latency_samples").get<std::size_t>());
  REQUIRE(times.size() == delays.size());
  CHECK(std::is_sorted(times.begin(), times.end()));
  CHECK(times.back() > times.front());
  CHECK(*std::max_element(delays.begin(), delays.end()) == d.at("latency_max_us").get<double>());

  REQUIRE(domain.call("app.release", Json{{"app", "RangeStop"}}).has_value());
  // The devices stay, without the application's connections.
  CHECK(port_connections(domain, "rsca/device/robot/IRSensor_1", "range_out") == 0);
  CHECK(port_connections(domain, "rsca/device/robot/DriveSystem_1", "command_in") == 0);
  domain.require_clean(pids_of(app));
}

TEST_CASE("StopCrash killed mid-run: the drive's own command deadline stops the robot",
          "[integration][robot][failure]") {
  TestDomain domain({TestDomain::shipped_nodes(1)[0], kRobotNode});
  // A threshold the robot never reaches before the wall: only the drive's safety can stop it.
  const Json app = launch(domain, 0.3, 0.05);
  REQUIRE(TestDomain::wait_for([&] { return robot(domain, "speed") > 0.25; }, 20s));
  const auto asked = std::chrono::steady_clock::now();
  const double before = robot(domain, "distance_to_wall");
  ::kill(static_cast<pid_t>(app.at("components")[0].at("pid").get<long>()), SIGKILL);
  const double to_kill = seconds_since(asked);
  REQUIRE(rests(domain));
  const double after = robot(domain, "distance_to_wall");
  const auto scenario = rsca::sim::default_scenario();
  const double braking = rsca::sim::braking_distance(scenario.robot, scenario.friction, 0.3);
  INFO("read " << before << " m from the wall " << to_kill * 1e3
               << " ms before the kill, rested at " << after << ", braking " << braking);
  CHECK(drive(domain).at("safety_stops") == 1);
  // At speed from the reading to the kill, then for the deadline (200 ms; the drive checks it
  // every 5 ms, allowed 50 ms late here), then braking: far from the wall.
  CHECK(before - after < 0.3 * (to_kill + 0.200 + 0.050) + braking);
  CHECK(after > 0.5);
  REQUIRE(domain.call("app.release", Json{{"app", "RangeStop"}}).has_value());
  domain.require_clean(pids_of(app));
}

TEST_CASE("the drive's emergency stop halts the robot within its braking distance and refuses "
          "commands until lifted",
          "[integration][robot]") {
  TestDomain domain({TestDomain::shipped_nodes(1)[0], kRobotNode});
  const Json app = launch(domain, 0.3, 0.05);
  REQUIRE(TestDomain::wait_for([&] { return robot(domain, "speed") > 0.25; }, 20s));
  const double asked_at = robot(domain, "sim_time");
  REQUIRE(domain
              .call("app.configure", Json{{"device", "robot:DriveSystem_1"},
                                          {"values", {{"emergency_stop", "true"}}}})
              .has_value());
  REQUIRE(rests(domain));
  const double rested_at = robot(domain, "sim_time");
  const double after = robot(domain, "distance_to_wall");
  // Judged in sim time, on the world's own trace (a point every 10 ms of it): the properties
  // are refreshed every 20 ms of wall time and the world's pacer may run steps back to back
  // after a late one, so wall time and a property read cannot say where the stop took effect.
  const Trace trace = robot_trace(domain, rested_at);
  const auto stopped =
      first_point_after(trace, asked_at, [](const TracePoint &p) { return p.commanded == 0; });
  REQUIRE(stopped.has_value());
  REQUIRE(*stopped > 0);
  const TracePoint last_driven = trace[*stopped - 1];
  const auto scenario = rsca::sim::default_scenario();
  const double braking = rsca::sim::braking_distance(scenario.robot, scenario.friction, 0.3);
  const double between_points = trace[*stopped].time - last_driven.time;
  INFO("driven at " << last_driven.speed << " m/s " << last_driven.distance_to_wall
                    << " m from the wall at " << last_driven.time << " s, stopped by "
                    << trace[*stopped].time << " s, rested at " << after << " m, braking "
                    << braking << " m");
  CHECK(last_driven.speed > 0.25);
  // At speed up to the step that took the stop (at most the gap between two points), then
  // braking; give or take a step's travel.
  CHECK(last_driven.distance_to_wall - after <
        0.3 * (between_points + scenario.time_step) + braking + 0.005);
  // StopCrash keeps commanding forward motion: refused while the stop holds.
  const long commands = drive(domain).at("commands_received").get<long>();
  CHECK(TestDomain::wait_for(
      [&] { return drive(domain).at("commands_received").get<long>() > commands + 5; }));
  CHECK(at_rest(domain));
  REQUIRE(domain.call("app.release", Json{{"app", "RangeStop"}}).has_value());
  domain.require_clean(pids_of(app));
}
