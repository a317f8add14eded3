// rsca-bench-rangestop-inprocess: the RangeStop experiment in one process with direct calls, the
// first way of tests/bench/rangestop_bench.py. The world steps in real time on one thread; a
// sensor thread reads the range every period and calls the controller, which calls the drive,
// which applies the command to the world; the delay is from the reading's timestamp to the
// drive's call. Output and shared rules: rangestop_common.hpp. Exit 0, 1 when a run failed.
#include "rangestop_common.hpp"

namespace {

using namespace rsca::bench::rangestop;
constexpr const char *kProgram = "rsca-bench-rangestop-inprocess";
constexpr const char *kWay = "inprocess";

// The drive: measures the delay, then applies the command.
struct Drive {
  rsca::sim::World &world;
  Delays &delays;

  void command(std::uint64_t reading_ns, double linear) {
    delays.record(reading_ns, now_ns());
    world.set_velocity(linear, 0.0);
  }
};

void run_once(const Settings &s, std::uint32_t run) {
  const std::uint64_t seed = s.first_seed + run;
  auto created = rsca::sim::World::create(scenario(s, seed));
  if (!created)
    die(kProgram, created.error().to_string());
  PacedWorld paced(std::move(*created));
  auto &world = paced.world();
  StopCrash controller(s);
  Delays delays;
  Drive drive{world, delays};
  std::uint64_t readings = 0;
  controller.start();
  {
    std::jthread sensor([&](std::stop_token stop) {
      every(stop, std::chrono::milliseconds(s.period_ms), [&] {
        const auto state = world.snapshot();
        const std::uint64_t stamp = now_ns();
        ++readings;
        drive.command(stamp, controller.on_range(state.ranges[0].range));
      });
    });
    if (!wait_for_rest(
            world, s, [&] { return controller.stopped(); }, [] { return false; }))
      die(kProgram, "run " + std::to_string(run) + ": the robot did not come to rest");
  }
  print_run(kWay, run, seed, world, controller.stop_range(), readings, delays.take());
}

} // namespace

int main(int argc, char **argv) {
  CLI::App app{"The RangeStop experiment in one process, direct calls, real time (JSON lines)"};
  Settings settings;
  add_options(app, settings);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError &e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  print_header(kWay, settings);
  for (std::uint32_t run = 0; run < settings.runs; ++run)
    run_once(settings, run);
  return 0;
}
