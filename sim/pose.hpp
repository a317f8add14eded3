// Planar poses and velocities of the robot. The world is 3-D (ODE), but the experiment only
// cares about where on the floor the robot is and which way it faces.
#pragma once

#include <Eigen/Geometry>

namespace rsca::sim {

// Position on the floor (m, world frame) and heading (rad, counter-clockwise from +x).
struct Pose2 {
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  double heading = 0.0;

  // The pose lifted to 3-D at height z, rotated about +z.
  Eigen::Isometry3d to_isometry(double z = 0.0) const;
  // The floor projection of a 3-D pose: its x-axis gives the heading.
  static Pose2 from_isometry(const Eigen::Isometry3d &pose);

  bool operator==(const Pose2 &) const = default;
};

// Body-frame velocity: forward speed (m/s) and yaw rate (rad/s, counter-clockwise).
struct Twist {
  double linear = 0.0;
  double angular = 0.0;

  bool operator==(const Twist &) const = default;
};

} // namespace rsca::sim
