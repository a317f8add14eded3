#include "sim/robot.hpp"

#include <cmath>
#include <tuple>

namespace rsca::sim {

namespace {

void set_pose(dBodyID body, const Eigen::Isometry3d &pose) {
  const Eigen::Vector3d &p = pose.translation();
  const Eigen::Quaterniond q(pose.linear());
  const dQuaternion ode_q{q.w(), q.x(), q.y(), q.z()};
  dBodySetPosition(body, p.x(), p.y(), p.z());
  dBodySetQuaternion(body, ode_q);
}

Eigen::Isometry3d pose_of(dBodyID body) {
  const dReal *p = dBodyGetPosition(body);
  const dReal *q = dBodyGetQuaternion(body);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translate(Eigen::Vector3d(p[0], p[1], p[2]));
  pose.rotate(Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized());
  return pose;
}

ode::Body make_body(dWorldID world, const dMass &mass, const Eigen::Isometry3d &pose) {
  ode::Body body(dBodyCreate(world));
  dBodySetMass(body.get(), &mass);
  set_pose(body.get(), pose);
  return body;
}

ode::Joint make_hinge(dWorldID world, dBodyID wheel, dBodyID chassis, const Eigen::Vector3d &anchor,
                      const Eigen::Vector3d &axis) {
  ode::Joint hinge(dJointCreateHinge(world, nullptr));
  // The wheel is body 1, so the hinge rate and the motor velocity are the wheel's spin relative
  // to the chassis: positive about the chassis' +y axis rolls the robot forward.
  dJointAttach(hinge.get(), wheel, chassis);
  dJointSetHingeAnchor(hinge.get(), anchor.x(), anchor.y(), anchor.z());
  dJointSetHingeAxis(hinge.get(), axis.x(), axis.y(), axis.z());
  return hinge;
}

} // namespace

Robot::Robot(dWorldID world, dSpaceID space, const RobotParams &params, const Pose2 &start,
             double initial_speed)
    : params_(params) {
  const auto &chassis = params.chassis;
  const auto &wheels = params.wheels;
  const double chassis_z = chassis.ground_clearance + chassis.size.z() / 2.0;
  const Eigen::Isometry3d chassis_pose = start.to_isometry(chassis_z);
  const Eigen::Matrix3d rotation = chassis_pose.linear();
  const Eigen::Vector3d forward = rotation * Eigen::Vector3d::UnitX();
  const Eigen::Vector3d lateral = rotation * Eigen::Vector3d::UnitY();

  dMass mass;
  dMassSetBoxTotal(&mass, chassis.mass, chassis.size.x(), chassis.size.y(), chassis.size.z());
  chassis_ = make_body(world, mass, chassis_pose);

  dMassSetSphereTotal(&mass, wheels.mass, wheels.radius);
  auto wheel_pose = [&](double side) {
    Eigen::Isometry3d pose = chassis_pose;
    pose.translate(
        Eigen::Vector3d(wheels.axle_offset, side * wheels.track / 2.0, wheels.radius - chassis_z));
    return pose;
  };
  const Eigen::Isometry3d left_pose = wheel_pose(+1.0);
  const Eigen::Isometry3d right_pose = wheel_pose(-1.0);
  left_wheel_ = make_body(world, mass, left_pose);
  right_wheel_ = make_body(world, mass, right_pose);

  chassis_box_.reset(dCreateBox(space, chassis.size.x(), chassis.size.y(), chassis.size.z()));
  dGeomSetBody(chassis_box_.get(), chassis_.get());
  caster_.reset(dCreateSphere(space, params.caster.radius));
  dGeomSetBody(caster_.get(), chassis_.get());
  dGeomSetOffsetPosition(caster_.get(), params.caster.offset, 0.0,
                         params.caster.radius - chassis_z);
  left_tire_.reset(dCreateSphere(space, wheels.radius));
  dGeomSetBody(left_tire_.get(), left_wheel_.get());
  right_tire_.reset(dCreateSphere(space, wheels.radius));
  dGeomSetBody(right_tire_.get(), right_wheel_.get());

  left_hinge_ =
      make_hinge(world, left_wheel_.get(), chassis_.get(), left_pose.translation(), lateral);
  right_hinge_ =
      make_hinge(world, right_wheel_.get(), chassis_.get(), right_pose.translation(), lateral);

  if (initial_speed != 0.0) {
    const Eigen::Vector3d v = initial_speed * forward;
    const Eigen::Vector3d spin = (initial_speed / wheels.radius) * lateral;
    for (dBodyID body : {chassis_.get(), left_wheel_.get(), right_wheel_.get()})
      dBodySetLinearVel(body, v.x(), v.y(), v.z());
    for (dBodyID body : {left_wheel_.get(), right_wheel_.get()})
      dBodySetAngularVel(body, spin.x(), spin.y(), spin.z());
  }
  drive(WheelPair{initial_speed / wheels.radius, initial_speed / wheels.radius});
}

void Robot::drive(WheelPair target) {
  // dWorldStep's LCP solver (Dantzig) gives up on a step ("LCP internal error, s <= 0") when two
  // rows reach their bounds at exactly the same moment, which two identical motors on a
  // symmetric robot do. A part in a billion less torque on the right motor breaks the tie and is
  // far below anything the experiment measures.
  constexpr double tie_break = 1.0 - 1e-9;
  for (auto [hinge, speed, torque] :
       {std::tuple{left_hinge_.get(), target.left, params_.motors.max_torque},
        std::tuple{right_hinge_.get(), target.right, params_.motors.max_torque * tie_break}}) {
    dJointSetHingeParam(hinge, dParamVel, speed);
    dJointSetHingeParam(hinge, dParamFMax, torque);
  }
}

Eigen::Isometry3d Robot::chassis_pose() const {
  return pose_of(chassis_.get());
}

Twist Robot::velocity() const {
  const dReal *v = dBodyGetLinearVel(chassis_.get());
  const dReal *w = dBodyGetAngularVel(chassis_.get());
  const Eigen::Vector3d forward = chassis_pose().linear() * Eigen::Vector3d::UnitX();
  return Twist{forward.dot(Eigen::Vector3d(v[0], v[1], v[2])), w[2]};
}

WheelPair Robot::wheel_speeds() const {
  return WheelPair{dJointGetHingeAngleRate(left_hinge_.get()),
                   dJointGetHingeAngleRate(right_hinge_.get())};
}

} // namespace rsca::sim
