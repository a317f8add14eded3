#include "sim/drive.hpp"

#include <algorithm>
#include <cmath>

namespace rsca::sim {

WheelPair wheel_targets(const RobotParams &robot, Twist command) {
  const double r = robot.wheels.radius;
  const double half_track = robot.wheels.track / 2.0;
  WheelPair wheels{(command.linear - command.angular * half_track) / r,
                   (command.linear + command.angular * half_track) / r};
  const double fastest = std::max(std::abs(wheels.left), std::abs(wheels.right));
  if (fastest > robot.motors.max_wheel_speed) {
    const double scale = robot.motors.max_wheel_speed / fastest;
    wheels.left *= scale;
    wheels.right *= scale;
  }
  return wheels;
}

Twist twist_of(const RobotParams &robot, WheelPair wheels) {
  const double r = robot.wheels.radius;
  return Twist{r * (wheels.left + wheels.right) / 2.0,
               r * (wheels.right - wheels.left) / robot.wheels.track};
}

double braking_deceleration(const RobotParams &robot, double friction) {
  const double r = robot.wheels.radius;
  const double wheels_mass = 2.0 * robot.wheels.mass;
  const double mass = robot.chassis.mass + wheels_mass;
  // A wheel's spin has to be braked too: I/r² = 2/5 m per wheel.
  const double effective_mass = mass + 0.4 * wheels_mass;
  const double torque_limited = 2.0 * robot.motors.max_torque / (r * effective_mass);

  // Moments about the caster: the share of the chassis' weight on the axle.
  const double axle = robot.wheels.axle_offset;
  const double caster = robot.caster.offset;
  const double axle_share = std::clamp((0.0 - caster) / (axle - caster), 0.0, 1.0);
  const double on_wheels = (wheels_mass + robot.chassis.mass * axle_share) * gravity;
  const double friction_limited = friction * on_wheels / mass;
  return std::min(torque_limited, friction_limited);
}

double braking_distance(const RobotParams &robot, double friction, double speed) {
  const double deceleration = braking_deceleration(robot, friction);
  if (deceleration <= 0.0)
    return speed == 0.0 ? 0.0 : HUGE_VAL;
  return speed * speed / (2.0 * deceleration);
}

double stop_tolerance(const RobotParams &robot, double friction, double speed, double latency) {
  return stop_tolerance_terms(robot, friction, speed, latency, 0.0, 0.0).total();
}

StopTolerance stop_tolerance_terms(const RobotParams &robot, double friction, double speed,
                                   double reaction_time, double transport_time,
                                   double noise_sigma) {
  return {std::abs(speed) * reaction_time, std::abs(speed) * transport_time,
          braking_distance(robot, friction, speed), 2.0 * noise_sigma};
}

} // namespace rsca::sim
