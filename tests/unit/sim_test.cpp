#include "sim/drive.hpp"
#include "sim/pacer.hpp"
#include "sim/scenario.hpp"
#include "sim/stop_trial.hpp"
#include "sim/world.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <numbers>
#include <thread>
#include <vector>

using namespace rsca;
using namespace rsca::sim;
using namespace std::chrono_literals;

namespace {

std::unique_ptr<World> make_world(const Scenario &scenario) {
  auto world = World::create(scenario);
  if (!world)
    FAIL("World::create failed: " << world.error().to_string());
  return std::move(*world);
}

// A wall whose near face passes through `face` with its normal pointing along `heading`.
WallSpec wall_facing(Eigen::Vector2d face, double heading) {
  WallSpec wall;
  const Eigen::Vector2d normal(std::cos(heading), std::sin(heading));
  wall.pose = Pose2{face + normal * wall.size.x() / 2.0, heading};
  return wall;
}

Scenario exact_scenario() {
  Scenario scenario = default_scenario();
  scenario.sensors.at(0).noise_sigma = 0.0;
  return scenario;
}

// Where the default forward sensor sits on the floor.
Eigen::Vector2d sensor_position(const WorldState &state, double forward = 0.10) {
  return state.pose.position +
         forward * Eigen::Vector2d(std::cos(state.pose.heading), std::sin(state.pose.heading));
}

// The most a speed can be and still be "at" max: the motors are a velocity constraint, so their
// speed may land a rounding error above the target, never more.
bool within_max(double wheel_speed, const RobotParams &robot) {
  return std::abs(wheel_speed) <= robot.motors.max_wheel_speed * (1.0 + 1e-6);
}

} // namespace

TEST_CASE("sim: the robot accelerates to the commanded speed within the motor limits",
          "[sim][drive]") {
  Scenario scenario = exact_scenario();
  scenario.walls.clear();
  const auto &robot = scenario.robot;
  const double max_speed = robot.motors.max_wheel_speed * robot.wheels.radius;
  const double acceleration = braking_deceleration(robot, scenario.friction);

  SECTION("a speed within the limit") {
    auto world = make_world(scenario);
    const auto command = world->set_velocity(0.3, 0.0);
    REQUIRE(command);
    CHECK(command->linear == Approx(0.3));
    // The torque limit makes the start a ramp, at the analytic acceleration.
    world->advance(50ms);
    CHECK(world->snapshot().velocity.linear == Approx(acceleration * 0.05).epsilon(0.1));
    for (int i = 0; i < 950; ++i) {
      world->step();
      const auto state = world->snapshot();
      REQUIRE(within_max(state.wheel_speed.left, robot));
      REQUIRE(within_max(state.wheel_speed.right, robot));
      REQUIRE(state.velocity.linear <= 0.3 * 1.01);
    }
    const auto state = world->snapshot();
    CHECK(state.time == Approx(1.0));
    CHECK(state.velocity.linear == Approx(0.3).epsilon(0.01));
    CHECK(state.commanded.linear == Approx(0.3));
    CHECK(state.commanded.angular == 0.0);
    CHECK(std::abs(state.pose.heading) < 1e-3);
    CHECK(state.pose.position.x() > 0.2);
  }

  SECTION("a speed beyond the limit is clamped to it") {
    auto world = make_world(scenario);
    const auto command = world->set_velocity(2.0, 0.0);
    REQUIRE(command);
    CHECK(command->linear == Approx(max_speed));
    double fastest = 0.0;
    for (int i = 0; i < 1000; ++i) {
      world->step();
      const auto state = world->snapshot();
      REQUIRE(within_max(state.wheel_speed.left, robot));
      REQUIRE(within_max(state.wheel_speed.right, robot));
      fastest = std::max(fastest, state.velocity.linear);
    }
    CHECK(world->snapshot().velocity.linear == Approx(max_speed).epsilon(0.01));
    CHECK(fastest <= max_speed * 1.01);
  }

  SECTION("turning keeps the curvature when a wheel would be too fast") {
    auto world = make_world(scenario);
    const auto command = world->set_velocity(0.5, 2.0);
    REQUIRE(command);
    CHECK(command->angular / command->linear == Approx(2.0 / 0.5));
    const auto targets = wheel_targets(robot, *command);
    CHECK(std::max(std::abs(targets.left), std::abs(targets.right)) ==
          Approx(robot.motors.max_wheel_speed));
    world->advance(1s);
    const auto state = world->snapshot();
    REQUIRE(within_max(state.wheel_speed.right, robot));
    CHECK(state.velocity.angular == Approx(command->angular).epsilon(0.05));
    CHECK(state.velocity.linear == Approx(command->linear).epsilon(0.05));
  }
}

TEST_CASE("sim: the same seed gives the same trajectory, another seed other readings",
          "[sim][determinism]") {
  Scenario scenario = default_scenario();
  scenario.sensors.at(0).noise_sigma = 0.01;
  scenario.walls = {wall_facing({1.2, 0.0}, 0.0)};
  auto run = [](Scenario s, std::uint64_t seed) {
    s.seed = seed;
    auto world = make_world(s);
    std::vector<WorldState> trajectory;
    REQUIRE(world->set_velocity(0.2, 0.3));
    for (int i = 0; i < 600; ++i) {
      if (i == 300)
        REQUIRE(world->set_velocity(0.1, -0.3));
      world->step();
      trajectory.push_back(world->snapshot());
    }
    return trajectory;
  };
  const auto first = run(scenario, 42);
  const auto again = run(scenario, 42);
  const auto other = run(scenario, 43);
  REQUIRE(first.size() == again.size());
  for (std::size_t i = 0; i < first.size(); ++i) {
    INFO("step " << i);
    // Bit for bit: operator== compares every double exactly.
    REQUIRE(first[i] == again[i]);
  }
  std::size_t same_readings = 0;
  for (std::size_t i = 0; i < first.size(); ++i) {
    REQUIRE(first[i].ranges.at(0).status == RangeStatus::Valid);
    same_readings += first[i].ranges.at(0).range == other[i].ranges.at(0).range;
    // The noise is the sensor's alone: the physics does not depend on the seed.
    REQUIRE(first[i].pose == other[i].pose);
  }
  CHECK(same_readings == 0);
}

TEST_CASE("sim: the range sensor reads the distance to the nearest wall", "[sim][range]") {
  Scenario scenario = exact_scenario();

  SECTION("a wall ahead, within 1 mm with no noise") {
    scenario.walls = {wall_facing({1.0, 0.0}, 0.0), wall_facing({1.4, 0.0}, 0.0)};
    auto world = make_world(scenario);
    world->step();
    const auto state = world->snapshot();
    const auto &reading = state.ranges.at(0);
    CHECK(reading.sensor == "front");
    CHECK(reading.status == RangeStatus::Valid);
    CHECK(reading.range == Approx(1.0 - sensor_position(state).x()).margin(0.001));
    const auto truth = world->true_range();
    REQUIRE(truth);
    CHECK(*truth == Approx(reading.range).margin(1e-9));
  }

  SECTION("a slanted wall, and a robot facing along y") {
    scenario.walls = {wall_facing({1.0, 0.0}, std::numbers::pi / 6)};
    auto slanted = make_world(scenario);
    slanted->step();
    auto state = slanted->snapshot();
    // The ray along +x crosses the face's plane where the face passes through (1, 0).
    CHECK(state.ranges.at(0).range == Approx(1.0 - sensor_position(state).x()).margin(0.001));

    scenario.start.heading = std::numbers::pi / 2;
    scenario.walls = {wall_facing({0.0, 0.8}, std::numbers::pi / 2)};
    auto turned = make_world(scenario);
    turned->step();
    state = turned->snapshot();
    CHECK(state.ranges.at(0).status == RangeStatus::Valid);
    CHECK(state.ranges.at(0).range == Approx(0.8 - sensor_position(state).y()).margin(0.001));
  }

  SECTION("noise stays around the distance") {
    scenario.sensors.at(0).noise_sigma = 0.01;
    scenario.walls = {wall_facing({1.0, 0.0}, 0.0)};
    auto world = make_world(scenario);
    double sum = 0.0, sum_squares = 0.0;
    const int n = 2000;
    const double truth = 1.0 - sensor_position(world->snapshot()).x();
    for (int i = 0; i < n; ++i) {
      world->step();
      const double error = world->snapshot().ranges.at(0).range - truth;
      sum += error;
      sum_squares += error * error;
    }
    CHECK(std::abs(sum / n) < 0.002);
    CHECK(std::sqrt(sum_squares / n) == Approx(0.01).epsilon(0.1));
  }

  SECTION("max range, flagged, when no wall is in range") {
    auto world = make_world(scenario); // the default wall is 1.9 m from the sensor
    world->step();
    auto reading = world->snapshot().ranges.at(0);
    CHECK(reading.status == RangeStatus::OutOfRange);
    CHECK(reading.range == scenario.sensors[0].max_range);
    const auto truth = world->true_range();
    REQUIRE(truth);
    CHECK(*truth == Approx(1.9).margin(0.001));

    scenario.walls.clear();
    auto empty = make_world(scenario);
    empty->step();
    CHECK(empty->snapshot().ranges.at(0).status == RangeStatus::OutOfRange);
    const auto none = empty->true_range();
    REQUIRE_FALSE(none);
    CHECK(none.error().diagnostics().at(0).rule == "sim-no-wall");
    CHECK_FALSE(empty->true_range(5));
  }

  SECTION("min range, flagged, when a wall is too close") {
    scenario.walls = {wall_facing({0.15, 0.0}, 0.0)};
    auto world = make_world(scenario);
    world->step();
    const auto reading = world->snapshot().ranges.at(0);
    CHECK(reading.status == RangeStatus::TooClose);
    CHECK(reading.range == scenario.sensors[0].min_range);
  }

  SECTION("the floor and the robot's own bodies are not seen") {
    RangeSensorParams down;
    down.name = "down";
    down.pitch = 0.5; // would meet the floor 0.07 m ahead
    down.noise_sigma = 0.0;
    RangeSensorParams back;
    back.name = "back";
    back.position = Eigen::Vector3d::Zero(); // inside the chassis, looking through the caster
    back.yaw = std::numbers::pi;
    back.noise_sigma = 0.0;
    scenario.sensors = {down, back};
    scenario.walls = {wall_facing({-1.0, 0.0}, std::numbers::pi)};
    auto world = make_world(scenario);
    world->step();
    const auto state = world->snapshot();
    CHECK(state.ranges.at(0).sensor == "down");
    CHECK(state.ranges.at(0).status == RangeStatus::OutOfRange);
    CHECK(state.ranges.at(1).status == RangeStatus::Valid);
    CHECK(state.ranges.at(1).range == Approx(state.pose.position.x() - (-1.0)).margin(0.001));
  }

  SECTION("a slow sensor keeps its reading between updates") {
    scenario.sensors.at(0).update_period = 0.038;
    scenario.walls = {wall_facing({1.0, 0.0}, 0.0)};
    auto world = make_world(scenario);
    REQUIRE(world->set_velocity(0.3, 0.0));
    std::vector<double> taken;
    for (int i = 0; i < 200; ++i) {
      world->step();
      const auto reading = world->snapshot().ranges.at(0);
      if (taken.empty() || reading.time != taken.back())
        taken.push_back(reading.time);
    }
    // The one at creation, then at 0.038, 0.076, ... s: five more in 0.2 s.
    REQUIRE(taken.size() == 6);
    for (std::size_t i = 0; i < taken.size(); ++i)
      CHECK(taken[i] == Approx(0.038 * static_cast<double>(i)).margin(1e-9));
  }
}

TEST_CASE("sim: the closed loop stops short of the threshold by at most the tolerance",
          "[sim][stop]") {
  Scenario scenario = default_scenario();
  const double sigma = 0.005;
  scenario.sensors.at(0).noise_sigma = sigma;
  StopTrial trial;
  trial.speed = 0.4;
  trial.threshold = 0.6;
  trial.period = 10ms;
  const double braking = braking_distance(scenario.robot, scenario.friction, trial.speed);
  const double tolerance = trial.speed * (0.010 + scenario.time_step) + braking;
  // A reading a few sigma high stops the robot late; a few sigma low, early.
  const double margin = 3 * sigma + 0.002;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    INFO("seed " << seed);
    scenario.seed = seed;
    auto world = make_world(scenario);
    Pacer pacer(*world);
    const auto outcome = run_stop_trial(pacer, trial);
    if (!outcome)
      FAIL(outcome.error().to_string());
    CHECK(outcome->predicted_tolerance == Approx(tolerance));
    CHECK(outcome->braking_distance == Approx(braking));
    CHECK(outcome->distance_to_wall <= trial.threshold);
    CHECK(outcome->distance_to_wall >= trial.threshold - (tolerance + margin));
    CHECK(outcome->overshoot == Approx(trial.threshold - outcome->distance_to_wall));
    CHECK(outcome->rest_time > outcome->command_time);
    CHECK(world->snapshot().velocity.linear < 0.001);
  }
}

TEST_CASE("sim: a longer control period lets the robot overshoot further", "[sim][stop]") {
  Scenario scenario = exact_scenario();
  const double speed = 0.4;
  const double braking = braking_distance(scenario.robot, scenario.friction, speed);
  // Where in the period the reading crosses the threshold decides how far the robot gets before
  // the check sees it: sweep the start over one long period of travel to see every phase. The
  // spacing is not a multiple of the short period's travel (4 mm), so it sees several phases too.
  auto overshoots = [&](std::chrono::milliseconds period) {
    std::vector<double> out;
    for (int k = 0; k < 10; ++k) {
      scenario.start.position.x() = -0.0043 * k;
      auto world = make_world(scenario);
      Pacer pacer(*world);
      StopTrial trial;
      trial.speed = speed;
      trial.period = period;
      const auto outcome = run_stop_trial(pacer, trial);
      if (!outcome)
        FAIL(outcome.error().to_string());
      INFO("period " << period.count() << " ms, start " << scenario.start.position.x());
      CHECK(outcome->overshoot >= braking - 0.001);
      CHECK(outcome->overshoot <= outcome->predicted_tolerance + 0.001);
      out.push_back(outcome->overshoot);
    }
    return out;
  };
  const auto fast = overshoots(10ms);
  const auto slow = overshoots(100ms);
  const double step = speed * 0.090; // speed × Δperiod
  const auto mean = [](const std::vector<double> &v) {
    double sum = 0.0;
    for (double x : v)
      sum += x;
    return sum / static_cast<double>(v.size());
  };
  const double max_growth =
      *std::max_element(slow.begin(), slow.end()) - *std::max_element(fast.begin(), fast.end());
  // The worst phase grows by up to speed × Δperiod, the average phase by half that.
  CHECK(max_growth >= 0.6 * step);
  CHECK(max_growth <= 1.05 * step);
  CHECK(mean(slow) - mean(fast) == Approx(step / 2).epsilon(0.3));
}

TEST_CASE("sim: an emergency stop brakes from the next step", "[sim][estop]") {
  Scenario scenario = exact_scenario();
  scenario.walls.clear();
  scenario.initial_speed = 0.5;
  const auto &robot = scenario.robot;
  auto world = make_world(scenario);
  world->advance(20ms);
  const auto before = world->snapshot();
  CHECK(before.velocity.linear == Approx(0.5).epsilon(0.01));
  CHECK(before.wheel_target.left == Approx(0.5 / robot.wheels.radius));

  world->emergency_stop();
  CHECK_FALSE(world->snapshot().e_stopped); // not before the next step
  world->step();
  const auto after = world->snapshot();
  CHECK(after.e_stopped);
  CHECK(after.wheel_target == WheelPair{0.0, 0.0});
  CHECK(after.commanded == Twist{0.0, 0.0});
  CHECK(after.velocity.linear < before.velocity.linear);

  const auto refused = world->set_velocity(0.3, 0.0);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().diagnostics().at(0).rule == "sim-e-stopped");

  const double braking = braking_distance(robot, scenario.friction, before.velocity.linear);
  int still = 0;
  while (still < 50) {
    world->step();
    const auto state = world->snapshot();
    REQUIRE(state.time < 5.0);
    REQUIRE(state.wheel_target == WheelPair{0.0, 0.0});
    still = std::abs(state.velocity.linear) < 0.001 ? still + 1 : 0;
  }
  const double travel = (world->snapshot().pose.position - before.pose.position).norm();
  CHECK(travel <= braking * 1.05 + 0.001);
  CHECK(travel >= braking * 0.9);

  world->reset_emergency_stop();
  world->step();
  CHECK_FALSE(world->snapshot().e_stopped);
  CHECK(world->set_velocity(0.3, 0.0));
}

TEST_CASE("sim: scenarios and commands out of their domain are refused", "[sim][errors]") {
  Scenario scenario = default_scenario();
  scenario.robot.chassis.mass = -1.0;
  scenario.sensors.at(0).min_range = 2.0;
  scenario.time_step = 0.0;
  const auto world = World::create(scenario);
  REQUIRE_FALSE(world);
  const auto &diagnostics = world.error().diagnostics();
  CHECK(diagnostics.size() == 3);
  for (const auto &d : diagnostics)
    CHECK(d.rule == "sim-scenario");
  CHECK(validate(default_scenario()));

  auto good = make_world(default_scenario());
  const auto nan = good->set_velocity(std::nan(""), 0.0);
  REQUIRE_FALSE(nan);
  CHECK(nan.error().diagnostics().at(0).rule == "sim-command");
}

TEST_CASE("sim: the pacer steps sim time and stops on request", "[sim][pacer]") {
  auto world = make_world(default_scenario());
  Pacer fast(*world, Pacing::AsFastAsPossible);
  CHECK(fast.run_for(250ms) == 250);
  CHECK(world->snapshot().steps == 250);
  CHECK(world->snapshot().time == Approx(0.25));

  std::stop_source stop;
  stop.request_stop();
  CHECK(fast.run_for(1s, stop.get_token()) == 0);

  // Real time at a thousand times the wall clock: the same steps, paced.
  Pacer paced(*world, Pacing::RealTime, 1000.0);
  CHECK(paced.run_for(100ms) == 100);
  CHECK(world->snapshot().steps == 350);
}

TEST_CASE("sim: commands and snapshots from another thread while the world steps",
          "[sim][threads]") {
  Scenario scenario = default_scenario();
  scenario.walls.clear();
  auto world = make_world(scenario);
  Pacer pacer(*world);
  std::jthread stepper([&pacer](std::stop_token stop) { pacer.run(stop); });
  double last_time = -1.0;
  for (int i = 0; i < 2000; ++i) {
    REQUIRE(world->set_velocity(0.2, i % 2 ? 0.1 : -0.1));
    const auto state = world->snapshot();
    REQUIRE(state.time >= last_time);
    REQUIRE(state.ranges.size() == 1);
    last_time = state.time;
  }
  stepper.request_stop();
  stepper.join();
  CHECK(world->snapshot().time >= last_time);
}
