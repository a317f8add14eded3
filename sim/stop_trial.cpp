#include "sim/stop_trial.hpp"

#include "sim/drive.hpp"

#include <cmath>
#include <optional>
#include <string>

namespace rsca::sim {

namespace {

tl::unexpected<Error> trial_error(std::string rule, std::string message) {
  return make_error(SourceLocation{"stop-trial", 0, 0}, std::move(rule), std::move(message));
}

// The range the controller sees at a check, or nothing when it is not below any threshold
// (out of range, or no wall at all for the exact distance).
std::optional<double> observed_range(const World &world, const StopTrial &trial) {
  if (trial.exact) {
    const auto exact = world.true_range(trial.sensor);
    return exact ? std::optional<double>(*exact) : std::nullopt;
  }
  const auto state = world.snapshot();
  if (trial.sensor >= state.ranges.size())
    return std::nullopt;
  const auto &reading = state.ranges[trial.sensor];
  if (reading.status == RangeStatus::OutOfRange)
    return std::nullopt;
  return reading.range;
}

} // namespace

Expected<StopOutcome> run_stop_trial(Pacer &pacer, const StopTrial &trial) {
  World &world = pacer.world();
  const Scenario &scenario = world.scenario();
  if (trial.sensor >= scenario.sensors.size())
    return trial_error("sim-sensor", "no range sensor " + std::to_string(trial.sensor));
  if (!(trial.period.count() > 0.0))
    return trial_error("sim-trial", "the control period must be positive");

  StopOutcome outcome;
  const double start = world.snapshot().time;
  const auto command = world.set_velocity(trial.speed, 0.0);
  if (!command)
    return tl::unexpected<Error>(command.error());
  const double speed = command->linear;

  for (;;) {
    pacer.run_for(trial.period);
    if (const auto range = observed_range(world, trial); range && *range < trial.threshold) {
      outcome.command_time = world.snapshot().time;
      outcome.command_range = *range;
      break;
    }
    if (world.snapshot().time - start > trial.timeout.count())
      return trial_error("sim-no-wall",
                         "the range never fell below " + std::to_string(trial.threshold) + " m");
  }
  if (auto stop = world.set_velocity(0.0, 0.0); !stop)
    return tl::unexpected<Error>(stop.error());

  const auto settle_steps = std::llround(trial.settle.count() / world.time_step());
  long long still = 0;
  double rest_since = 0.0;
  const std::chrono::duration<double> one_step(world.time_step());
  while (still < settle_steps) {
    pacer.run_for(one_step);
    const auto state = world.snapshot();
    if (std::abs(state.velocity.linear) < trial.rest_speed) {
      if (still++ == 0)
        rest_since = state.time;
    } else {
      still = 0;
    }
    if (state.time - start > trial.timeout.count())
      return trial_error("sim-no-rest", "the robot did not come to rest");
  }

  const auto distance = world.true_range(trial.sensor);
  if (!distance)
    return tl::unexpected<Error>(distance.error());
  const auto &sensor = scenario.sensors[trial.sensor];
  const double latency =
      trial.period.count() + (trial.exact ? 0.0 : sensor.update_period) + world.time_step();
  outcome.speed = speed;
  outcome.rest_time = rest_since;
  outcome.rest_pose = world.snapshot().pose;
  outcome.distance_to_wall = *distance;
  outcome.overshoot = trial.threshold - *distance;
  outcome.braking_distance = braking_distance(scenario.robot, scenario.friction, speed);
  outcome.reaction_time = latency;
  outcome.predicted_tolerance = stop_tolerance(scenario.robot, scenario.friction, speed, latency);
  return outcome;
}

} // namespace rsca::sim
