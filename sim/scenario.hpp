// What a simulated run is made of: the robot, its sensors, the walls, the floor and the seed.
// All quantities are SI (m, kg, s, rad, N·m). The defaults are a small indoor robot driving
// toward a wall 2 m ahead with one forward IR range sensor.
#pragma once

#include "common/diagnostic.hpp"
#include "sim/pose.hpp"

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace rsca::sim {

// A static box. Its local x-axis is the thickness, so the face toward -x is the one a robot
// standing in front of an unrotated wall sees.
struct WallSpec {
  Pose2 pose{Eigen::Vector2d(2.05, 0.0), 0.0}; // centre on the floor
  Eigen::Vector3d size{0.1, 4.0, 0.5};         // thickness, length, height
};

struct ChassisParams {
  double mass = 2.0;
  Eigen::Vector3d size{0.20, 0.16, 0.05}; // length (x), width (y), height (z)
  double ground_clearance = 0.01;         // gap under the box when level
};

// The two driven wheels share an axle across the chassis, ahead of its centre of mass so the
// caster carries the rest of the weight and the robot does not rock on its axle.
struct WheelParams {
  double radius = 0.035;
  double mass = 0.05;
  double track = 0.18;       // distance between the wheels' contact points
  double axle_offset = 0.04; // axle position along the chassis x-axis from its centre
};

// The wheel motors: a velocity servo whose torque is limited. The torque limit is what makes
// acceleration and braking finite; the speed limit caps the commanded wheel speed.
struct MotorLimits {
  double max_wheel_speed = 0.5 / 0.035; // rad/s: 0.5 m/s on the default wheels
  double max_torque = 0.075;            // N·m per wheel
};

// A frictionless sphere fixed under the rear of the chassis.
struct CasterParams {
  double radius = 0.015;
  double offset = -0.08; // along the chassis x-axis from its centre
};

struct RobotParams {
  ChassisParams chassis;
  WheelParams wheels;
  MotorLimits motors;
  CasterParams caster;
};

// An IR range sensor (the defaults are a Sharp GP2Y0A02: 0.2–1.5 m nominal; 0.1 m is where its
// output stops being monotonic, so nearer than that reads as "too close").
struct RangeSensorParams {
  std::string name = "front";
  // Mount in the chassis frame: the ray starts at `position` and points along the chassis x-axis
  // turned by `yaw` (about z), then tilted down by `pitch` (about the turned y-axis).
  Eigen::Vector3d position{0.10, 0.0, 0.0};
  double yaw = 0.0;
  double pitch = 0.0;
  double min_range = 0.1;
  double max_range = 1.5;
  double noise_sigma = 0.005; // Gaussian, m; 0 gives the exact distance
  // How often the sensor produces a new reading; 0 means every step. The GP2Y0A02 updates about
  // every 38 ms, which adds to the staleness a controller sees.
  double update_period = 0.0;
};

struct Scenario {
  Pose2 start;                // chassis centre on the floor and heading
  double initial_speed = 0.0; // forward, m/s: the robot starts rolling and commanded at it
  RobotParams robot;
  std::vector<RangeSensorParams> sensors{RangeSensorParams{}};
  std::vector<WallSpec> walls{WallSpec{}};
  double friction = 0.8;    // Coulomb mu between the wheels and the floor
  double time_step = 0.001; // s, fixed
  std::uint64_t seed = 1;   // the noise generator's; physics itself draws no random numbers
};

inline Scenario default_scenario() {
  return Scenario{};
}

// Every parameter in its domain (positive masses and sizes, min < max range, ...), each problem
// as a diagnostic with rule "sim-scenario".
Expected<void> validate(const Scenario &scenario);

} // namespace rsca::sim
