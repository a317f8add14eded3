#include "sim/pose.hpp"

#include <cmath>

namespace rsca::sim {

Eigen::Isometry3d Pose2::to_isometry(double z) const {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translate(Eigen::Vector3d(position.x(), position.y(), z));
  pose.rotate(Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()));
  return pose;
}

Pose2 Pose2::from_isometry(const Eigen::Isometry3d &pose) {
  const Eigen::Vector3d forward = pose.linear() * Eigen::Vector3d::UnitX();
  return Pose2{pose.translation().head<2>(), std::atan2(forward.y(), forward.x())};
}

} // namespace rsca::sim
