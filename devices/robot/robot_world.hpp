// The simulated robot a node's robot devices are attached to: one World (sim/), stepped in real
// time on its own thread, so that devices and controllers in other processes meet it on real
// timers as they would meet hardware. The node's Robot device owns it; IRSensor and DriveSystem
// find it through current(). It keeps a trace of the run for reports.
#pragma once

#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "common/diagnostic.hpp"
#include "sim/pacer.hpp"
#include "sim/world.hpp"

namespace rsca::robot {

struct TracePoint {
  double time = 0;             // s of sim time
  double distance_to_wall = 0; // m, exact, along the front sensor's ray
  double speed = 0;            // m/s, measured
  double commanded = 0;        // m/s
};

class RobotWorld {
public:
  static Expected<std::shared_ptr<RobotWorld>> start(const sim::Scenario &scenario,
                                                     sim::Pacing pacing);
  ~RobotWorld();
  RobotWorld(const RobotWorld &) = delete;
  RobotWorld &operator=(const RobotWorld &) = delete;

  sim::World &world() { return *world_; }
  std::vector<TracePoint> trace() const;
  double distance_to_wall() const;

  // The world of this node's Robot device, or null when there is none (yet).
  static std::shared_ptr<RobotWorld> current();
  static void set_current(std::shared_ptr<RobotWorld> world);

private:
  explicit RobotWorld(std::unique_ptr<sim::World> world, sim::Pacing pacing);
  void run(std::stop_token stop);

  std::unique_ptr<sim::World> world_;
  sim::Pacer pacer_;
  mutable std::mutex trace_mutex_;
  std::vector<TracePoint> trace_;
  std::jthread stepper_; // last: stopped before the rest goes
};

} // namespace rsca::robot
