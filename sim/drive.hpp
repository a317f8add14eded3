// Differential-drive kinematics and the braking model the tolerance of a stop is explained by.
#pragma once

#include "sim/pose.hpp"
#include "sim/scenario.hpp"

namespace rsca::sim {

inline constexpr double gravity = 9.81; // m/s², the world's

// Wheel angular speeds (rad/s, positive rolls the robot forward).
struct WheelPair {
  double left = 0.0;
  double right = 0.0;

  bool operator==(const WheelPair &) const = default;
};

// The wheel speeds that realise `command`, scaled down together when one would exceed the
// motors' max speed so the robot keeps the commanded curvature rather than veering.
WheelPair wheel_targets(const RobotParams &robot, Twist command);

// The body velocity the wheel speeds give when they roll without slipping.
Twist twist_of(const RobotParams &robot, WheelPair wheels);

// The steady deceleration when both motors brake at their torque limit, or the one friction
// allows if that is lower. The friction limit takes the wheels' static share of the weight
// (braking shifts weight onto them, so it is conservative); the torque limit counts the wheels'
// rotational inertia (the wheels are spheres: I = 2/5 m r²).
double braking_deceleration(const RobotParams &robot, double friction);

// v² / 2a: how far the robot rolls from `speed` once the motors target zero.
double braking_distance(const RobotParams &robot, double friction, double speed);

// How far past a range threshold a periodic controller lets the robot get: it keeps driving at
// `speed` for up to `latency` after the reading crosses the threshold (control period + sensor
// update period + the one step before a command takes effect), then brakes.
double stop_tolerance(const RobotParams &robot, double friction, double speed, double latency);

// The same bound term by term, for a controller reading a real sensor through middleware: how
// far the robot drives at `speed` while a reading waits to be acted on (`reaction_time`: control
// period, sensor update, a world step) and while the command travels to the drive
// (`transport_time`), how far it then brakes, and two sigmas of the sensor's noise, by which the
// reading itself may come early. The RangeStop report, the robot tests and rsca-sim-run all
// take the terms from here.
struct StopTolerance {
  double reaction = 0.0;
  double transport = 0.0;
  double braking = 0.0;
  double sensor_noise = 0.0;
  double total() const { return reaction + transport + braking + sensor_noise; }
};
StopTolerance stop_tolerance_terms(const RobotParams &robot, double friction, double speed,
                                   double reaction_time, double transport_time, double noise_sigma);

} // namespace rsca::sim
