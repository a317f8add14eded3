// Steps a World against the wall clock: in real time (for hardware in the loop, where devices
// and controllers run on real timers) or as fast as the machine allows (for batches of runs).
#pragma once

#include "sim/world.hpp"

#include <chrono>
#include <cstdint>
#include <stop_token>

namespace rsca::sim {

enum class Pacing : std::uint8_t { RealTime, AsFastAsPossible };

class Pacer {
public:
  // `rate` is sim seconds per wall-clock second in real time (2 runs twice as fast); ignored
  // as fast as possible.
  explicit Pacer(World &world, Pacing pacing = Pacing::AsFastAsPossible, double rate = 1.0);

  // Steps through `duration` of sim time (rounded to whole steps) or until `stop` is requested;
  // returns the steps taken. In real time each step waits until the wall clock, counted from
  // this call, has caught up with it; a step that falls behind is not skipped, the next ones
  // run back to back until caught up.
  std::uint64_t run_for(std::chrono::duration<double> duration, std::stop_token stop = {});
  // Steps until `stop` is requested (as fast as possible, that is a busy loop).
  std::uint64_t run(std::stop_token stop);

  World &world() const { return world_; }
  Pacing pacing() const { return pacing_; }

private:
  std::uint64_t run_steps(std::uint64_t limit, const std::stop_token &stop);

  World &world_;
  Pacing pacing_;
  double rate_;
};

} // namespace rsca::sim
