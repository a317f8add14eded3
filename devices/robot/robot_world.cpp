#include "robot/robot_world.hpp"

namespace rsca::robot {
namespace {

constexpr std::chrono::milliseconds kTraceEvery{10};
constexpr std::size_t kTraceLimit = 60'000; // 10 minutes of sim time

std::mutex current_mutex;
std::shared_ptr<RobotWorld> current_world;

} // namespace

Expected<std::shared_ptr<RobotWorld>> RobotWorld::start(const sim::Scenario &scenario,
                                                        sim::Pacing pacing) {
  auto world = sim::World::create(scenario);
  if (!world)
    return tl::unexpected(world.error());
  return std::shared_ptr<RobotWorld>(new RobotWorld(std::move(*world), pacing));
}

RobotWorld::RobotWorld(std::unique_ptr<sim::World> world, sim::Pacing pacing)
    : world_(std::move(world)), pacer_(*world_, pacing),
      stepper_([this](std::stop_token stop) { run(std::move(stop)); }) {}

RobotWorld::~RobotWorld() {
  stepper_.request_stop();
  if (stepper_.joinable())
    stepper_.join();
}

void RobotWorld::run(std::stop_token stop) {
  while (!stop.stop_requested()) {
    pacer_.run_for(kTraceEvery, stop);
    const auto state = world_->snapshot();
    std::lock_guard lock(trace_mutex_);
    if (trace_.size() < kTraceLimit)
      trace_.push_back({state.time, world_->true_range(0).value_or(-1.0), state.velocity.linear,
                        state.commanded.linear});
  }
}

std::vector<TracePoint> RobotWorld::trace() const {
  std::lock_guard lock(trace_mutex_);
  return trace_;
}

double RobotWorld::distance_to_wall() const {
  return world_->true_range(0).value_or(-1.0);
}

std::shared_ptr<RobotWorld> RobotWorld::current() {
  std::lock_guard lock(current_mutex);
  return current_world;
}

void RobotWorld::set_current(std::shared_ptr<RobotWorld> world) {
  std::lock_guard lock(current_mutex);
  current_world = std::move(world);
}

} // namespace rsca::robot
