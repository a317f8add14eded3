// The StopCrash experiment in process: drive toward a wall, check the range every control
// period like a periodic controller, command a stop once it is below the threshold, and see
// where the robot comes to rest. The baseline the distributed version is compared with.
#pragma once

#include "common/diagnostic.hpp"
#include "sim/pacer.hpp"
#include "sim/pose.hpp"

#include <chrono>
#include <cstddef>

namespace rsca::sim {

struct StopTrial {
  double speed = 0.3;     // m/s, commanded forward
  double threshold = 0.6; // m: stop when the range is below it
  std::chrono::duration<double> period = std::chrono::milliseconds(10); // control period
  std::size_t sensor = 0;
  // Compare the exact distance instead of the sensor's (noisy, possibly stale) reading.
  bool exact = false;
  double rest_speed = 0.001; // m/s: slower than this (for `settle`) counts as at rest
  std::chrono::duration<double> settle = std::chrono::milliseconds(50);
  std::chrono::duration<double> timeout = std::chrono::seconds(120); // of sim time
};

struct StopOutcome {
  double speed = 0.0;         // m/s, as commanded after the motors' limit
  double command_time = 0.0;  // sim time the stop was commanded
  double command_range = 0.0; // the range that triggered it
  double rest_time = 0.0;     // sim time the robot came to rest
  Pose2 rest_pose;
  double distance_to_wall = 0.0; // exact, along the sensor's ray, at rest
  double overshoot = 0.0;        // threshold - distance_to_wall: how far past the threshold
  double braking_distance = 0.0; // analytic, from the commanded speed
  double reaction_time = 0.0;    // period + sensor update period + one step (s)
  // Speed × (period + sensor update period + one step) + braking distance: the bound the
  // overshoot should stay under, give or take the sensor's noise.
  double predicted_tolerance = 0.0;
};

// Runs the trial on `pacer`'s world from its current state. Fails with "sim-no-wall" when the
// range never drops below the threshold before the timeout, "sim-no-rest" when the robot does
// not come to rest, or the world's error when a command is refused.
Expected<StopOutcome> run_stop_trial(Pacer &pacer, const StopTrial &trial);

} // namespace rsca::sim
