// Admission and placement time of the planner: N components (a chain of connections) over D
// GPP devices on D/10 nodes, with capacities, for both strategies, with and without timing
// admission. The goal: 1,000 components over 100 devices in under 50 ms, growing no
// worse than about components x devices.
#include <memory>

#include <benchmark/benchmark.h>

#include "allocator/planner.hpp"

namespace {

using namespace rsca;
using allocator::Nanos;

struct Fixture {
  profile::SoftPkg spd;
  profile::ResolvedSoftPkg pkg;
  allocator::DomainState domain;
  allocator::PlanRequest request;
};

// One software package every component instantiates: Linux, 5% of a CPU, 32 MiB.
std::unique_ptr<Fixture> make_fixture(int components, int devices, bool periodic) {
  auto f = std::make_unique<Fixture>();
  profile::Implementation impl;
  impl.id = "cpp";
  impl.os.push_back({"Linux", ""});
  profile::ResourceDemand demand;
  demand.utilization = 0.05;
  demand.memory_bytes = 32ull << 20;
  impl.resource_demand = demand;
  f->spd.name = "Worker";
  f->spd.implementations.push_back(impl);
  f->pkg.implementations.push_back({&f->spd.implementations.front(), nullptr, {}});
  for (int d = 0; d < devices; ++d) {
    allocator::Device device;
    device.id = "node" + std::to_string(d / 10) + ":GPP_" + std::to_string(d % 10);
    device.node = "node" + std::to_string(d / 10);
    device.kind = "gpp";
    device.properties.push_back({"os_name", "os_name", "Linux", profile::Action::Eq});
    device.capacity = {{allocator::kCpuCapacity, 400.0}, {allocator::kMemCapacity, 16384.0}};
    device.cpus = 4;
    f->domain.emplace(device.id, allocator::DeviceState{device, {}});
  }
  for (int c = 0; c < components; ++c) {
    allocator::ComponentRequest request;
    request.instance = "w" + std::to_string(c);
    request.softpkg = &f->pkg;
    if (periodic) {
      profile::Timing timing;
      timing.period = Duration{Nanos(10'000'000)};
      timing.execution_time = Duration{Nanos(500'000)};
      request.timing = timing;
    }
    f->request.components.push_back(std::move(request));
    if (c > 0)
      f->request.affinities.push_back({"w" + std::to_string(c - 1), "w" + std::to_string(c), 1.0});
  }
  return f;
}

void run(benchmark::State &state, allocator::Strategy strategy, bool periodic) {
  const auto components = static_cast<int>(state.range(0));
  const auto devices = static_cast<int>(state.range(1));
  auto f = make_fixture(components, devices, periodic);
  for (auto _ : state) {
    auto plan = allocator::make_plan(f->domain, f->request, {strategy});
    if (!plan)
      state.SkipWithError("no plan");
    benchmark::DoNotOptimize(plan);
  }
  state.SetComplexityN(static_cast<benchmark::IterationCount>(components) * devices);
  state.counters["components"] = components;
  state.counters["devices"] = devices;
}

void BM_PlanPack(benchmark::State &state) {
  run(state, allocator::Strategy::Pack, false);
}
void BM_PlanSpread(benchmark::State &state) {
  run(state, allocator::Strategy::Spread, false);
}
void BM_PlanPackPeriodic(benchmark::State &state) {
  run(state, allocator::Strategy::Pack, true);
}

// N components over D devices: (10,10) (100,10) (100,100) (1000,100).
void sizes(benchmark::internal::Benchmark *b) {
  for (auto [n, d] : {std::pair{10, 10}, {100, 10}, {100, 100}, {1000, 100}})
    b->Args({n, d});
  b->Unit(benchmark::kMillisecond)->Complexity(benchmark::oN);
}

BENCHMARK(BM_PlanPack)->Apply(sizes);
BENCHMARK(BM_PlanSpread)->Apply(sizes);
BENCHMARK(BM_PlanPackPeriodic)->Apply(sizes);

} // namespace

BENCHMARK_MAIN();
