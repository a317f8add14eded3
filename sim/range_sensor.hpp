// An IR range sensor: an ODE ray from a mount on the chassis, cast against the walls only, so
// the robot's own bodies and the floor never shadow it. Internal to rsca_sim: World owns it.
#pragma once

#include "sim/ode_handles.hpp"
#include "sim/scenario.hpp"
#include "sim/world_state.hpp"

#include <optional>
#include <random>
#include <span>

#include <Eigen/Geometry>

namespace rsca::sim {

class RangeSensor {
public:
  explicit RangeSensor(const RangeSensorParams &params);

  // Distance from the mount along the ray to the nearest wall no farther than `length`.
  std::optional<double> cast(const Eigen::Isometry3d &chassis, std::span<const dGeomID> walls,
                             double length);

  // Takes a new reading when one is due at `time` (every call when the update period is 0).
  void update(double time, const Eigen::Isometry3d &chassis, std::span<const dGeomID> walls,
              std::mt19937_64 &rng);

  const RangeReading &latest() const { return latest_; }
  const RangeSensorParams &params() const { return params_; }

private:
  RangeSensorParams params_;
  Eigen::Isometry3d mount_;
  ode::Geom ray_; // in no space: it takes no part in the physics
  double next_update_ = 0.0;
  RangeReading latest_;
};

} // namespace rsca::sim
