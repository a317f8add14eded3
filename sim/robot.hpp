// The differential-drive robot as ODE bodies: a box chassis, two sphere wheels on hinges driven
// by velocity motors with a torque limit, and a frictionless caster sphere under the chassis.
// Internal to rsca_sim: World owns it and serialises access.
#pragma once

#include "sim/drive.hpp"
#include "sim/ode_handles.hpp"
#include "sim/pose.hpp"
#include "sim/scenario.hpp"

#include <Eigen/Geometry>

namespace rsca::sim {

class Robot {
public:
  Robot(dWorldID world, dSpaceID space, const RobotParams &params, const Pose2 &start,
        double initial_speed);

  // The motors servo the wheels toward `target` with at most the torque limit, which both
  // accelerates and brakes.
  void drive(WheelPair target);

  Eigen::Isometry3d chassis_pose() const;
  Twist velocity() const;
  WheelPair wheel_speeds() const;
  // Wheel contacts use the floor's friction; the caster slides freely.
  bool is_caster(dGeomID geom) const { return geom == caster_.get(); }

private:
  RobotParams params_;
  // Declaration order is teardown order reversed: joints, then geoms, then bodies.
  ode::Body chassis_;
  ode::Body left_wheel_;
  ode::Body right_wheel_;
  ode::Geom chassis_box_;
  ode::Geom caster_;
  ode::Geom left_tire_;
  ode::Geom right_tire_;
  ode::Joint left_hinge_;
  ode::Joint right_hinge_;
};

} // namespace rsca::sim
