#include "sim/scenario.hpp"

#include <cmath>
#include <string>

namespace rsca::sim {

namespace {

class Checker {
public:
  void positive(double value, const std::string &what) {
    if (!(std::isfinite(value) && value > 0.0))
      fail(what + " must be positive and finite, is " + std::to_string(value));
  }
  void non_negative(double value, const std::string &what) {
    if (!(std::isfinite(value) && value >= 0.0))
      fail(what + " must be zero or positive and finite, is " + std::to_string(value));
  }
  void finite(double value, const std::string &what) {
    if (!std::isfinite(value))
      fail(what + " must be finite");
  }
  void fail(std::string message) {
    error_.add(Diagnostic{SourceLocation{"scenario", 0, 0}, "sim-scenario", std::move(message)});
  }
  Expected<void> result() const {
    if (error_.empty())
      return {};
    return tl::unexpected<Error>(error_);
  }

private:
  Error error_;
};

void check_robot(Checker &check, const RobotParams &robot) {
  check.positive(robot.chassis.mass, "chassis mass");
  for (int i = 0; i < 3; ++i)
    check.positive(robot.chassis.size[i], "chassis size");
  check.non_negative(robot.chassis.ground_clearance, "chassis ground clearance");
  check.positive(robot.wheels.radius, "wheel radius");
  check.positive(robot.wheels.mass, "wheel mass");
  check.positive(robot.wheels.track, "wheel track");
  check.finite(robot.wheels.axle_offset, "wheel axle offset");
  check.positive(robot.motors.max_wheel_speed, "max wheel speed");
  check.positive(robot.motors.max_torque, "max torque");
  check.positive(robot.caster.radius, "caster radius");
  check.finite(robot.caster.offset, "caster offset");
  // The caster hangs from the chassis: it must reach the floor without lifting the wheels.
  const double chassis_bottom = robot.chassis.ground_clearance;
  if (robot.caster.radius * 2.0 < chassis_bottom)
    check.fail("caster diameter is smaller than the chassis' ground clearance");
  const double half_height = robot.chassis.size.z() / 2.0;
  if (robot.wheels.radius < chassis_bottom ||
      robot.wheels.radius > chassis_bottom + 2 * half_height)
    check.fail("wheel axle must lie within the chassis' height");
  if (std::abs(robot.caster.offset - robot.wheels.axle_offset) < 1e-3)
    check.fail("caster and wheel axle must not be at the same place along the chassis");
}

void check_sensor(Checker &check, const RangeSensorParams &sensor) {
  const std::string what = "range sensor \"" + sensor.name + "\" ";
  for (int i = 0; i < 3; ++i)
    check.finite(sensor.position[i], what + "position");
  check.finite(sensor.yaw, what + "yaw");
  check.finite(sensor.pitch, what + "pitch");
  check.non_negative(sensor.min_range, what + "min range");
  check.positive(sensor.max_range, what + "max range");
  if (sensor.min_range >= sensor.max_range)
    check.fail(what + "min range must be below its max range");
  check.non_negative(sensor.noise_sigma, what + "noise sigma");
  check.non_negative(sensor.update_period, what + "update period");
}

} // namespace

Expected<void> validate(const Scenario &scenario) {
  Checker check;
  check.finite(scenario.start.position.x(), "start x");
  check.finite(scenario.start.position.y(), "start y");
  check.finite(scenario.start.heading, "start heading");
  check.finite(scenario.initial_speed, "initial speed");
  check_robot(check, scenario.robot);
  if (std::abs(scenario.initial_speed) >
      scenario.robot.motors.max_wheel_speed * scenario.robot.wheels.radius)
    check.fail("initial speed exceeds what the wheels' max speed allows");
  for (const auto &sensor : scenario.sensors)
    check_sensor(check, sensor);
  for (const auto &wall : scenario.walls) {
    check.finite(wall.pose.position.x(), "wall x");
    check.finite(wall.pose.position.y(), "wall y");
    check.finite(wall.pose.heading, "wall heading");
    for (int i = 0; i < 3; ++i)
      check.positive(wall.size[i], "wall size");
  }
  check.non_negative(scenario.friction, "friction");
  check.positive(scenario.time_step, "time step");
  return check.result();
}

} // namespace rsca::sim
