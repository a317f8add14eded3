// The simulated world: a flat floor, box walls, one differential-drive robot and its range
// sensors, stepped with a fixed time step. Deterministic: the same scenario (seed included) and
// the same commands at the same steps give a bit-identical trajectory.
//
// Thread safety: every member function may be called from any thread. One thread steps; others
// command and read. A command given while a step runs waits for it and takes effect at the next.
#pragma once

#include "common/diagnostic.hpp"
#include "sim/scenario.hpp"
#include "sim/world_state.hpp"

#include <chrono>
#include <cstddef>
#include <memory>

namespace rsca::sim {

class World {
  struct Impl;
  // Lets make_unique reach the constructor while only create() can call it.
  class Key {
    friend class World;
    explicit Key() = default;
  };

public:
  // Fails (rule "sim-scenario") when a parameter is out of its domain.
  static Expected<std::unique_ptr<World>> create(const Scenario &scenario);
  World(Key, std::unique_ptr<Impl> impl); // for create() only
  ~World();
  World(const World &) = delete;
  World &operator=(const World &) = delete;

  // One fixed time step: apply the latest command, collide, integrate, read the sensors.
  void step();
  // As many steps as fit `duration` (rounded to the nearest whole step).
  void advance(std::chrono::duration<double> duration);

  // Forward speed (m/s) and yaw rate (rad/s), from the next step on, turned into wheel speeds
  // scaled to the motors' max speed; returns the velocity that will be commanded. Fails (rule
  // "sim-e-stopped") after an emergency stop until it is reset, or on a non-finite value.
  Expected<Twist> set_velocity(double linear, double angular);
  // From the next step on, the motors target zero with their full torque and commands are
  // refused: latched until reset_emergency_stop().
  void emergency_stop();
  // Lifts the latch at the next step; the robot stays commanded to zero until set_velocity.
  void reset_emergency_stop();

  // The state after the last step (after creation: the start, with the first sensor readings).
  WorldState snapshot() const;
  // Ground truth: the exact distance along sensor `sensor`'s ray to the nearest wall, however
  // far. Fails with "sim-sensor" for an unknown index, "sim-no-wall" when the ray hits none.
  Expected<double> true_range(std::size_t sensor = 0) const;

  const Scenario &scenario() const;
  double time_step() const;

private:
  std::unique_ptr<Impl> impl_;
};

} // namespace rsca::sim
