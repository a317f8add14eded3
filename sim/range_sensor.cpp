#include "sim/range_sensor.hpp"

#include <algorithm>

namespace rsca::sim {

RangeSensor::RangeSensor(const RangeSensorParams &params)
    : params_(params), mount_(Eigen::Isometry3d::Identity()),
      ray_(dCreateRay(nullptr, params.max_range)) {
  mount_.translate(params.position);
  mount_.rotate(Eigen::AngleAxisd(params.yaw, Eigen::Vector3d::UnitZ()));
  mount_.rotate(Eigen::AngleAxisd(params.pitch, Eigen::Vector3d::UnitY()));
  latest_.sensor = params.name;
  latest_.range = params.max_range;
}

std::optional<double> RangeSensor::cast(const Eigen::Isometry3d &chassis,
                                        std::span<const dGeomID> walls, double length) {
  const Eigen::Isometry3d ray_pose = chassis * mount_;
  const Eigen::Vector3d origin = ray_pose.translation();
  const Eigen::Vector3d direction = ray_pose.linear() * Eigen::Vector3d::UnitX();
  dGeomRaySetLength(ray_.get(), length);
  dGeomRaySet(ray_.get(), origin.x(), origin.y(), origin.z(), direction.x(), direction.y(),
              direction.z());
  std::optional<double> nearest;
  for (dGeomID wall : walls) {
    dContactGeom hit;
    // A ray reports its nearest intersection with a box, at `depth` from its start.
    if (dCollide(ray_.get(), wall, 1, &hit, sizeof(hit)) > 0 && (!nearest || hit.depth < *nearest))
      nearest = hit.depth;
  }
  return nearest;
}

void RangeSensor::update(double time, const Eigen::Isometry3d &chassis,
                         std::span<const dGeomID> walls, std::mt19937_64 &rng) {
  // Half a nanosecond of slack: `time` is a multiple of the time step, the period may not be.
  if (time + 5e-10 < next_update_)
    return;
  next_update_ += params_.update_period;
  if (next_update_ <= time)
    next_update_ = time + params_.update_period;

  latest_.time = time;
  const auto hit = cast(chassis, walls, params_.max_range);
  if (!hit) {
    latest_.status = RangeStatus::OutOfRange;
    latest_.range = params_.max_range;
  } else if (*hit < params_.min_range) {
    latest_.status = RangeStatus::TooClose;
    latest_.range = params_.min_range;
  } else {
    double range = *hit;
    // Only noisy sensors draw, so adding an exact sensor leaves the others' noise unchanged.
    if (params_.noise_sigma > 0.0)
      range += std::normal_distribution<double>(0.0, params_.noise_sigma)(rng);
    latest_.status = RangeStatus::Valid;
    latest_.range = std::clamp(range, params_.min_range, params_.max_range);
  }
}

} // namespace rsca::sim
