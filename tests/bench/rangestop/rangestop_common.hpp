// What the two baselines of the RangeStop benchmark (tests/bench/rangestop_bench.py) share, so
// that they run the experiment the robot node's devices and StopCrash run through rsca:
// - the world: the Robot device's scenario (devices/robot/robot_device.cpp): the default robot,
//   the wall's near face `wall_distance` ahead of the sensor, the sensor's noise, the seed of
//   the run; stepped in real time on a thread of its own (as RobotWorld does);
// - the sensor: every period, the front range of the latest step, stamped right after it is read
//   (IRSensor); the controller: StopCrash (components/stop_crash), forward at `speed` until a
//   reading is below `threshold`, then zero, latched; the drive: a command's delay is now minus
//   its reading's timestamp, taken as the command arrives, before it is applied (DriveSystem);
// - time: the system clock in ns, the devices' clock (port::now_ns);
// - the end of a run: a stop was commanded and the robot has been slower than 1 mm/s for 50 ms of
//   sim time; the stopping distance is then the exact distance to the wall along the sensor's ray.
// Output: one JSON object a line on stdout: first the settings and the predicted tolerance, then
// one per run.
#pragma once

#include "sim/drive.hpp"
#include "sim/pacer.hpp"
#include "sim/scenario.hpp"
#include "sim/world.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <mutex>
#include <stop_token>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace rsca::bench::rangestop {

struct Settings {
  double speed = 0.3;           // m/s, StopCrash's forward speed
  double threshold = 0.6;       // m, StopCrash's stop threshold
  std::uint32_t period_ms = 20; // the sensor's period
  double wall_distance = 2.0;   // m, from the sensor to the wall's near face (the robot DCD's)
  double noise = 0.005;         // m, the sensor's Gaussian noise (the Robot device's default)
  std::uint32_t runs = 20;
  std::uint64_t first_seed = 1; // run i (from 0) uses seed first_seed + i
  double timeout_s = 60;        // wall clock, for one run to come to rest
};

inline void add_options(CLI::App &app, Settings &s) {
  app.add_option("--speed", s.speed, "forward speed, m/s")->capture_default_str();
  app.add_option("--threshold", s.threshold, "stop below this range, m")->capture_default_str();
  app.add_option("--period-ms", s.period_ms, "sensor period, ms")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000));
  app.add_option("--wall-distance", s.wall_distance, "sensor to wall at the start, m")
      ->capture_default_str();
  app.add_option("--noise", s.noise, "sensor noise sigma, m")->capture_default_str();
  app.add_option("--runs", s.runs, "runs")->capture_default_str();
  app.add_option("--first-seed", s.first_seed, "seed of the first run (then +1 a run)")
      ->capture_default_str();
  app.add_option("--timeout", s.timeout_s, "wall-clock seconds for a run to come to rest")
      ->capture_default_str();
}

// The Robot device's world (Robot::restart in devices/robot/robot_device.cpp).
inline sim::Scenario scenario(const Settings &s, std::uint64_t seed) {
  sim::Scenario scenario;
  scenario.seed = seed;
  scenario.sensors[0].noise_sigma = s.noise;
  const double thickness = scenario.walls[0].size.x();
  scenario.walls[0].pose.position.x() =
      scenario.robot.chassis.size.x() / 2 + s.wall_distance + thickness / 2;
  return scenario;
}

// The devices' clock (port::now_ns).
inline std::uint64_t now_ns() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}

[[noreturn]] inline void die(const std::string &program, const std::string &what) {
  std::cerr << program << ": " << what << "\n";
  std::exit(1);
}

// The first line of the output: what was run and what the stop should look like.
inline void print_header(const std::string &way, const Settings &s) {
  const auto sc = scenario(s, s.first_seed);
  const double period = s.period_ms / 1000.0;
  nlohmann::ordered_json out = {
      {"way", way},
      {"settings",
       {{"speed", s.speed},
        {"threshold", s.threshold},
        {"period_ms", s.period_ms},
        {"wall_distance", s.wall_distance},
        {"noise", s.noise},
        {"runs", s.runs},
        {"first_seed", s.first_seed}}},
      {"braking_distance", sim::braking_distance(sc.robot, sc.friction, s.speed)},
      {"predicted_tolerance", sim::stop_tolerance(sc.robot, sc.friction, s.speed, period)}};
  std::cout << out.dump() << std::endl;
}

// StopCrash's decision (components/stop_crash/stop_crash.cpp): forward at `speed` while the
// reading is at or above `threshold`, then zero, latched until start().
class StopCrash {
public:
  explicit StopCrash(const Settings &s) : threshold_(s.threshold), speed_(s.speed) {}

  void start() { stopped_ = false; }
  double on_range(double range) {
    if (!stopped_.load() && range < threshold_) {
      stop_range_ = range;
      stopped_ = true;
    }
    return stopped_.load() ? 0.0 : speed_;
  }
  bool stopped() const { return stopped_.load(); }
  double stop_range() const { return stop_range_.load(); }

private:
  double threshold_;
  double speed_;
  std::atomic<bool> stopped_{false};
  std::atomic<double> stop_range_{0.0};
};

// A world stepped in real time on its own thread for as long as it lives (RobotWorld).
class PacedWorld {
public:
  explicit PacedWorld(std::unique_ptr<sim::World> world)
      : world_(std::move(world)), pacer_(*world_, sim::Pacing::RealTime),
        stepper_([this](std::stop_token stop) { pacer_.run(std::move(stop)); }) {}
  ~PacedWorld() {
    stepper_.request_stop();
    if (stepper_.joinable())
      stepper_.join();
  }
  PacedWorld(const PacedWorld &) = delete;
  PacedWorld &operator=(const PacedWorld &) = delete;

  sim::World &world() { return *world_; }

private:
  std::unique_ptr<sim::World> world_;
  sim::Pacer pacer_;
  std::jthread stepper_; // last: stopped before the world goes
};

// Calls `tick` every `period` until `stop` is requested, on a fixed schedule (a late tick does
// not shift the later ones).
template <typename Tick>
void every(const std::stop_token &stop, std::chrono::milliseconds period, Tick tick) {
  auto due = std::chrono::steady_clock::now();
  while (!stop.stop_requested()) {
    tick();
    due += period;
    std::this_thread::sleep_until(due);
  }
}

// The drive's delay measurements, from any thread.
class Delays {
public:
  void record(std::uint64_t reading_ns, std::uint64_t now) {
    const double us = now >= reading_ns ? static_cast<double>(now - reading_ns) / 1e3 : 0.0;
    std::lock_guard lock(mutex_);
    us_.push_back(us);
  }
  std::vector<double> take() {
    std::lock_guard lock(mutex_);
    return std::exchange(us_, {});
  }

private:
  std::mutex mutex_;
  std::vector<double> us_;
};

// Waits until a stop was commanded (`stopped`) and the robot has been at rest for 50 ms of sim
// time; false after `timeout_s` of wall clock, or as soon as `failed` says so.
template <typename Stopped, typename Failed>
bool wait_for_rest(const sim::World &world, const Settings &s, Stopped stopped, Failed failed) {
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(s.timeout_s));
  double still_since = -1.0;
  while (std::chrono::steady_clock::now() < deadline && !failed()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1)); // pacing a poll of the world
    const auto state = world.snapshot();
    if (stopped() && std::abs(state.velocity.linear) < 0.001) {
      if (still_since < 0)
        still_since = state.time;
      if (state.time - still_since >= 0.05)
        return true;
    } else {
      still_since = -1.0;
    }
  }
  return false;
}

// One run's line.
inline void print_run(const std::string &way, std::uint32_t run, std::uint64_t seed,
                      const sim::World &world, double stop_range, std::uint64_t readings,
                      const std::vector<double> &delays_us) {
  const auto distance = world.true_range(0);
  const auto state = world.snapshot();
  nlohmann::ordered_json out = {{"way", way},
                                {"run", run},
                                {"seed", seed},
                                {"distance_to_wall", distance ? *distance : -1.0},
                                {"stop_range", stop_range},
                                {"sim_time", state.time},
                                {"readings", readings},
                                {"commands", delays_us.size()},
                                {"delays_us", delays_us}};
  std::cout << out.dump() << std::endl;
}

} // namespace rsca::bench::rangestop
