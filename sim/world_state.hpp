// A copy of everything observable about the world after a step, taken under the world's lock so
// threads other than the one stepping can read it consistently.
#pragma once

#include "sim/drive.hpp"
#include "sim/pose.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace rsca::sim {

enum class RangeStatus : std::uint8_t {
  Valid,      // a wall within [min, max] range
  OutOfRange, // nothing hit up to max range: the reading is max range
  TooClose,   // a wall nearer than min range: the reading is min range
};

struct RangeReading {
  std::string sensor;
  double range = 0.0; // m, noisy when the sensor has noise, always within [min, max] range
  RangeStatus status = RangeStatus::OutOfRange;
  double time = 0.0; // sim time the reading was taken

  bool operator==(const RangeReading &) const = default;
};

struct WorldState {
  double time = 0.0; // s of sim time
  std::uint64_t steps = 0;
  Pose2 pose;            // chassis centre of mass on the floor
  Twist velocity;        // measured, chassis frame
  Twist commanded;       // what the motors are driving toward (after clamping; zero once e-stopped)
  WheelPair wheel_speed; // measured hinge rates
  WheelPair wheel_target; // the motors' target speeds during the last step
  bool e_stopped = false;
  std::vector<RangeReading> ranges; // one per sensor, in scenario order

  bool operator==(const WorldState &) const = default;
};

} // namespace rsca::sim
