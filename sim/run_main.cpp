// rsca-sim-run: the StopCrash experiment on the default scenario, in process and headless.
// Prints where the robot came to rest as JSON; exit 0, 1 when the run failed, 2 on bad usage.
#include "sim/drive.hpp"
#include "sim/pacer.hpp"
#include "sim/stop_trial.hpp"
#include "sim/world.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdint>
#include <iostream>

namespace {

nlohmann::ordered_json to_json(const rsca::sim::Pose2 &pose) {
  return {{"x", pose.position.x()}, {"y", pose.position.y()}, {"heading", pose.heading}};
}

nlohmann::ordered_json tolerance_json(const rsca::sim::StopTolerance &t) {
  return {{"reaction", t.reaction},
          {"transport", t.transport},
          {"braking", t.braking},
          {"sensor_noise", t.sensor_noise}};
}

} // namespace

int main(int argc, char **argv) {
  CLI::App app{"Drives the simulated robot toward the wall, stops it when the exact range drops "
               "below the threshold, and prints where it came to rest (JSON)"};
  double speed = 0.3;
  double threshold = 0.6;
  double period_ms = 10.0;
  std::uint64_t seed = 1;
  bool real_time = false;
  app.add_option("--speed", speed, "forward speed, m/s (clamped to the motors' limit)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--threshold", threshold, "stop when the range is below this, m")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--period-ms", period_ms, "control period (sim time), ms")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 3600e3));
  app.add_option("--seed", seed, "the world's noise seed (the exact range used here has none)")
      ->capture_default_str();
  app.add_flag("--real-time", real_time, "pace the simulation to the wall clock");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError &e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  using namespace rsca::sim;
  Scenario scenario = default_scenario();
  scenario.seed = seed;
  auto world = World::create(scenario);
  if (!world) {
    std::cerr << "rsca-sim-run: " << world.error().to_string() << "\n";
    return 1;
  }
  const auto start_range = (*world)->true_range();
  Pacer pacer(**world, real_time ? Pacing::RealTime : Pacing::AsFastAsPossible);
  StopTrial trial;
  trial.speed = speed;
  trial.threshold = threshold;
  trial.period = std::chrono::duration<double, std::milli>(period_ms);
  trial.exact = true;
  const auto wall_clock = std::chrono::steady_clock::now();
  const auto outcome = run_stop_trial(pacer, trial);
  const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - wall_clock;
  if (!outcome) {
    std::cerr << "rsca-sim-run: " << outcome.error().to_string() << "\n";
    return 1;
  }

  const auto state = (*world)->snapshot();
  nlohmann::ordered_json out = {
      {"scenario",
       {{"speed", outcome->speed},
        {"threshold", threshold},
        {"period_ms", period_ms},
        {"time_step_ms", scenario.time_step * 1000.0},
        {"start_distance_to_wall", start_range ? *start_range : 0.0},
        {"seed", seed},
        {"pacing", real_time ? "real-time" : "as-fast-as-possible"}}},
      {"stop_command", {{"time", outcome->command_time}, {"range", outcome->command_range}}},
      {"rest", {{"time", outcome->rest_time}, {"position", to_json(outcome->rest_pose)}}},
      {"distance_to_wall", outcome->distance_to_wall},
      {"overshoot", outcome->overshoot},
      {"braking_distance", outcome->braking_distance},
      {"predicted_tolerance", outcome->predicted_tolerance},
      // What the exact range used here leaves out, and a controller reading the real sensor
      // (the one rsca's IRSensor device serves) has to allow for.
      {"sensor_noise_sigma", scenario.sensors.front().noise_sigma},
      // The terms of the tolerance through middleware, with no transport time: the caller adds
      // its own (speed x the latency it measured).
      {"tolerance_terms", tolerance_json(rsca::sim::stop_tolerance_terms(
                              scenario.robot, scenario.friction, outcome->speed,
                              outcome->reaction_time, 0.0, scenario.sensors.front().noise_sigma))},
      {"within_tolerance",
       outcome->overshoot >= 0.0 && outcome->overshoot <= outcome->predicted_tolerance},
      {"sim_time", state.time},
      {"steps", state.steps},
      {"wall_clock_s", elapsed.count()},
  };
  std::cout << out.dump(2) << "\n";
  return 0;
}
