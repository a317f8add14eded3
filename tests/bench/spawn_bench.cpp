// The GPP's launch path starts each process from a thread of its own (process/spawn_thread.hpp):
// what that hand-off adds to a spawn, next to the spawn alone (the baseline) in the same run.
// Each iteration starts /bin/true and waits for its exit through the pidfd.
#include <poll.h>
#include <sys/wait.h>

#include <benchmark/benchmark.h>

#include "process/spawn.hpp"
#include "process/spawn_thread.hpp"

namespace {

using rsca::process::Command;
using rsca::process::Group;

void run_true(benchmark::State &state) {
  auto child = rsca::process::spawn(Command{.program = "/bin/true"}, Group::Own);
  if (!child) {
    state.SkipWithError(child.error().to_string().c_str());
    return;
  }
  pollfd p{child->pidfd.get(), POLLIN, 0};
  ::poll(&p, 1, -1);
  ::waitpid(child->pid, nullptr, 0);
}

void BM_Spawn(benchmark::State &state) {
  for (auto _ : state)
    run_true(state);
}

void BM_SpawnFromSpawnThread(benchmark::State &state) {
  rsca::process::SpawnThread spawner;
  for (auto _ : state)
    spawner.run([&] { run_true(state); });
}

// The hand-off alone: a task that does nothing, run on the thread.
void BM_SpawnThreadHandOff(benchmark::State &state) {
  rsca::process::SpawnThread spawner;
  for (auto _ : state)
    benchmark::DoNotOptimize(spawner.run([] { return 1; }));
}

} // namespace

BENCHMARK(BM_Spawn)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SpawnFromSpawnThread)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SpawnThreadHandOff)->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
