#include "sim/pacer.hpp"

#include <cmath>
#include <limits>
#include <thread>

namespace rsca::sim {

Pacer::Pacer(World &world, Pacing pacing, double rate)
    : world_(world), pacing_(pacing), rate_(rate > 0.0 && std::isfinite(rate) ? rate : 1.0) {}

std::uint64_t Pacer::run_for(std::chrono::duration<double> duration, std::stop_token stop) {
  const double steps = std::round(duration.count() / world_.time_step());
  return steps > 0.0 ? run_steps(static_cast<std::uint64_t>(steps), stop) : 0;
}

std::uint64_t Pacer::run(std::stop_token stop) {
  return run_steps(std::numeric_limits<std::uint64_t>::max(), stop);
}

std::uint64_t Pacer::run_steps(std::uint64_t limit, const std::stop_token &stop) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  const std::chrono::duration<double> wall_per_step(world_.time_step() / rate_);
  std::uint64_t done = 0;
  while (done < limit && !stop.stop_requested()) {
    world_.step();
    ++done;
    if (pacing_ == Pacing::RealTime) {
      // Counted from the start rather than step by step, so sleep overshoot does not add up.
      const auto due = start + std::chrono::duration_cast<Clock::duration>(
                                   wall_per_step * static_cast<double>(done));
      std::this_thread::sleep_until(due);
    }
  }
  return done;
}

} // namespace rsca::sim
