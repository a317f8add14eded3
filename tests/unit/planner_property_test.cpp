// Randomized property tests of the placement planner: thousands of small random domains and
// applications (fixed seeds), each checked against an independent model of the constraints and
// against a brute-force search. Silent on success; a failure prints the seed and the case.
#include "allocator/planner.hpp"
#include "allocator/resource_allocator.hpp"
#include "planner_state.hpp"

#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

using namespace rsca;
using namespace rsca::allocator;

namespace {

using PkgPtr = std::shared_ptr<const profile::ResolvedSoftPkg>;
constexpr double kTolerance = 1e-9;
const char *const kOsNames[] = {"Linux", "QNX"};

// ---- the model: integers only, so the checks below are exact -----------------------------------

struct DeviceModel {
  std::string id;
  std::string node;
  std::string os;
  int cpu = 0; // percent
  int mem = 0; // MiB
  int cpu_used = 0;
  int mem_used = 0;
};

struct ImplModel {
  std::string id;
  std::string os; // empty: any
  int cpu = 0;
  int mem = 0;
};

struct ComponentModel {
  std::string instance;
  std::vector<ImplModel> impls;
  std::string group; // hostcollocation, empty for none
};

struct Case {
  std::uint32_t seed = 0;
  Strategy strategy = Strategy::Pack;
  std::vector<DeviceModel> devices;
  std::vector<ComponentModel> components;
};

int pick(std::mt19937 &rng, int lo, int hi) {
  return std::uniform_int_distribution<int>(lo, hi)(rng);
}

bool chance(std::mt19937 &rng, int percent) {
  return pick(rng, 1, 100) <= percent;
}

// 1-4 GPPs on 1-3 nodes, some already loaded; 1-5 components of 1-2 implementations that differ
// in os and demand, some in one of two collocation groups.
Case random_case(std::uint32_t seed) {
  std::mt19937 rng(seed);
  Case c;
  c.seed = seed;
  c.strategy = chance(rng, 50) ? Strategy::Pack : Strategy::Spread;
  const int nodes = pick(rng, 1, 3);
  const int devices = pick(rng, 1, 4);
  for (int d = 0; d < devices; ++d) {
    DeviceModel m;
    m.node = "n" + std::to_string(pick(rng, 1, nodes));
    m.id = m.node + ":GPP_" + std::to_string(d);
    m.os = kOsNames[pick(rng, 0, 1)];
    m.cpu = pick(rng, 10, 100);
    m.mem = pick(rng, 64, 1024);
    if (chance(rng, 30)) {
      m.cpu_used = pick(rng, 0, m.cpu / 2);
      m.mem_used = pick(rng, 0, m.mem / 2);
    }
    c.devices.push_back(m);
  }
  const int components = pick(rng, 1, 5);
  for (int k = 0; k < components; ++k) {
    ComponentModel m;
    m.instance = "c" + std::to_string(k);
    const int impls = pick(rng, 1, 2);
    for (int i = 0; i < impls; ++i) {
      ImplModel impl;
      impl.id = "impl" + std::to_string(i);
      impl.os = chance(rng, 20) ? "" : kOsNames[pick(rng, 0, 1)];
      impl.cpu = chance(rng, 15) ? 0 : pick(rng, 1, 60);
      impl.mem = chance(rng, 15) ? 0 : pick(rng, 1, 512);
      m.impls.push_back(impl);
    }
    const int g = pick(rng, 0, 9);
    m.group = g < 3 ? "g0" : (g < 5 ? "g1" : "");
    c.components.push_back(m);
  }
  return c;
}

std::string describe(const Case &c) {
  std::ostringstream out;
  out << "seed " << c.seed << ", strategy " << to_string(c.strategy) << "\n";
  for (const auto &d : c.devices)
    out << "  device " << d.id << " os " << d.os << " cpu " << d.cpu_used << "/" << d.cpu << " mem "
        << d.mem_used << "/" << d.mem << "\n";
  for (const auto &m : c.components) {
    out << "  component " << m.instance << (m.group.empty() ? "" : " group " + m.group) << ":";
    for (const auto &i : m.impls)
      out << " [" << i.id << " os " << (i.os.empty() ? "any" : i.os) << " cpu " << i.cpu << " mem "
          << i.mem << "]";
    out << "\n";
  }
  return out.str();
}

// ---- the planner's input, built from the model --------------------------------------------------

PkgPtr softpkg_of(const std::string &name, const std::vector<ImplModel> &impls) {
  auto spd = std::make_shared<profile::SoftPkg>();
  spd->id = spd->name = name;
  for (const auto &m : impls) {
    profile::Implementation impl;
    impl.id = m.id;
    if (!m.os.empty())
      impl.os.push_back({m.os, ""});
    if (m.cpu > 0 || m.mem > 0) {
      impl.resource_demand.emplace();
      if (m.cpu > 0)
        impl.resource_demand->utilization = m.cpu / 100.0;
      if (m.mem > 0)
        impl.resource_demand->memory_bytes = static_cast<std::uint64_t>(m.mem) * 1024 * 1024;
    }
    spd->implementations.push_back(impl);
  }
  auto pkg = std::make_shared<profile::ResolvedSoftPkg>();
  pkg->spd = spd;
  for (const auto &impl : spd->implementations)
    pkg->implementations.push_back({&impl, nullptr, {}});
  return pkg;
}

Device device_of(const DeviceModel &m) {
  Device d;
  d.id = m.id;
  d.node = m.node;
  d.kind = "gpp";
  d.properties.push_back({"os_name", "os_name", m.os, profile::Action::Eq});
  d.capacity[kCpuCapacity] = m.cpu;
  d.capacity[kMemCapacity] = m.mem;
  return d;
}

struct Built {
  DomainState state;
  std::vector<PkgPtr> pkgs; // keeps request.components[*].softpkg alive
  PlanRequest request;
};

Built build(const Case &c) {
  Built b;
  for (const auto &m : c.devices) {
    DeviceState s{device_of(m), {}};
    if (m.cpu_used > 0)
      s.load.allocated[kCpuCapacity] = m.cpu_used;
    if (m.mem_used > 0)
      s.load.allocated[kMemCapacity] = m.mem_used;
    b.state.emplace(m.id, std::move(s));
  }
  for (const auto &m : c.components) {
    b.pkgs.push_back(softpkg_of(m.instance, m.impls));
    ComponentRequest r;
    r.instance = m.instance;
    r.softpkg = b.pkgs.back().get();
    r.collocation = m.group;
    b.request.components.push_back(std::move(r));
  }
  return b;
}

PlanOptions options_of(const Case &c) {
  PlanOptions o;
  o.strategy = c.strategy;
  return o;
}

// ---- independent checks -------------------------------------------------------------------------

bool os_fits(const ImplModel &impl, const DeviceModel &device) {
  return impl.os.empty() || impl.os == device.os;
}

// Every (implementation, device) choice per component, pruned only where a partial choice already
// breaks os, capacity or collocation (which no completion can repair).
bool brute_force(const Case &c) {
  std::vector<int> cpu_free, mem_free;
  for (const auto &d : c.devices) {
    cpu_free.push_back(d.cpu - d.cpu_used);
    mem_free.push_back(d.mem - d.mem_used);
  }
  std::map<std::string, std::string> group_node;
  std::function<bool(std::size_t)> place = [&](std::size_t k) {
    if (k == c.components.size())
      return true;
    const auto &m = c.components[k];
    for (const auto &impl : m.impls)
      for (std::size_t d = 0; d < c.devices.size(); ++d) {
        const auto &dev = c.devices[d];
        if (!os_fits(impl, dev) || impl.cpu > cpu_free[d] || impl.mem > mem_free[d])
          continue;
        const bool opens = !m.group.empty() && group_node.count(m.group) == 0;
        if (!m.group.empty() && !opens && group_node[m.group] != dev.node)
          continue;
        if (opens)
          group_node[m.group] = dev.node;
        cpu_free[d] -= impl.cpu;
        mem_free[d] -= impl.mem;
        const bool found = place(k + 1);
        cpu_free[d] += impl.cpu;
        mem_free[d] += impl.mem;
        if (opens)
          group_node.erase(m.group);
        if (found)
          return true;
      }
    return false;
  };
  return place(0);
}

double amount(const std::map<std::string, double> &amounts, const std::string &name) {
  auto it = amounts.find(name);
  return it == amounts.end() ? 0.0 : it->second;
}

// Why the plan breaks a constraint of the model, or nothing when it satisfies them all.
std::optional<std::string> violation(const Case &c, const Built &b, const Plan &plan) {
  std::ostringstream why;
  if (plan.placements.size() != c.components.size())
    return "placements: " + std::to_string(plan.placements.size());
  std::map<std::string, std::pair<int, int>> used; // device -> (cpu, mem), from the model
  for (const auto &d : c.devices)
    used[d.id] = {d.cpu_used, d.mem_used};
  std::map<std::string, std::string> group_node;
  for (std::size_t k = 0; k < c.components.size(); ++k) {
    const auto &m = c.components[k];
    const auto &p = plan.placements[k];
    if (p.instance != m.instance)
      return "placement " + std::to_string(k) + " is " + p.instance;
    const DeviceModel *dev = nullptr;
    for (const auto &d : c.devices)
      if (d.id == p.device)
        dev = &d;
    if (dev == nullptr)
      return m.instance + " on unknown device " + p.device;
    if (p.node != dev->node)
      return m.instance + ": node " + p.node + ", its device is on " + dev->node;
    const ImplModel *impl = nullptr;
    const auto &impls = b.pkgs[k]->spd->implementations;
    for (std::size_t i = 0; i < impls.size(); ++i)
      if (&impls[i] == p.implementation)
        impl = &m.impls[i];
    if (impl == nullptr)
      return m.instance + ": implementation not of its package";
    if (!os_fits(*impl, *dev))
      return m.instance + ": " + impl->id + " (os " + impl->os + ") on " + dev->os;
    if (std::abs(amount(p.demand, kCpuCapacity) - impl->cpu) > kTolerance ||
        amount(p.demand, kMemCapacity) != impl->mem)
      return m.instance + ": demand differs from " + impl->id;
    if (!m.group.empty()) {
      auto [it, inserted] = group_node.emplace(m.group, dev->node);
      if (!inserted && it->second != dev->node)
        return "group " + m.group + " on " + it->second + " and " + dev->node;
    }
    used[dev->id].first += impl->cpu;
    used[dev->id].second += impl->mem;
  }
  DomainState committed = b.state;
  commit(committed, plan);
  for (const auto &d : c.devices) {
    const auto &[cpu, mem] = used[d.id];
    if (cpu > d.cpu || mem > d.mem)
      why << d.id << " over-committed: cpu " << cpu << "/" << d.cpu << " mem " << mem << "/"
          << d.mem << "\n";
    const auto &allocated = committed.at(d.id).load.allocated;
    if (std::abs(amount(allocated, kCpuCapacity) - cpu) > kTolerance ||
        std::abs(amount(allocated, kMemCapacity) - mem) > kTolerance)
      why << d.id << " commit allocated cpu " << amount(allocated, kCpuCapacity) << " mem "
          << amount(allocated, kMemCapacity) << ", expected " << cpu << " and " << mem << "\n";
  }
  if (why.str().empty())
    return std::nullopt;
  return why.str();
}

std::string describe(const Plan &plan) {
  std::ostringstream out;
  for (const auto &p : plan.placements)
    out << "  " << p.instance << " -> " << p.device << " (" << p.implementation->id << ")\n";
  return out.str();
}

// Equality within kTolerance, a capacity absent counting as zero (release leaves zeros behind).
bool close_load(const DomainState &a, const DomainState &b) {
  if (a.size() != b.size())
    return false;
  for (const auto &[id, s] : a) {
    auto it = b.find(id);
    if (it == b.end())
      return false;
    std::set<std::string> names;
    for (const auto &[name, v] : s.load.allocated)
      names.insert(name);
    for (const auto &[name, v] : it->second.load.allocated)
      names.insert(name);
    for (const auto &name : names)
      if (std::abs(amount(s.load.allocated, name) - amount(it->second.load.allocated, name)) >
          kTolerance)
        return false;
    if (!(s.load.cpu_tasks == it->second.load.cpu_tasks))
      return false;
  }
  return true;
}

std::string describe(const DomainState &state) {
  std::ostringstream out;
  for (const auto &[id, s] : state) {
    out << "  " << id << ":";
    for (const auto &[name, v] : s.load.allocated)
      out << " " << name << "=" << v;
    out << "\n";
  }
  return out.str();
}

// A ResourceAllocator holding the case's devices, the preloads reserved by a background
// application pinned to each loaded device.
struct LoadedAllocator {
  ResourceAllocator allocator;
  std::vector<PkgPtr> pkgs;
};

bool load(LoadedAllocator &out, const Case &c) {
  std::map<std::string, std::vector<Device>> by_node;
  for (const auto &d : c.devices)
    by_node[d.node].push_back(device_of(d));
  for (auto &[node, devices] : by_node)
    out.allocator.set_node_devices(node, std::move(devices));
  PlanRequest background;
  for (const auto &d : c.devices) {
    if (d.cpu_used == 0 && d.mem_used == 0)
      continue;
    out.pkgs.push_back(softpkg_of("bg_" + d.id, {ImplModel{"bg", "", d.cpu_used, d.mem_used}}));
    ComponentRequest r;
    r.instance = "bg_" + d.id;
    r.softpkg = out.pkgs.back().get();
    r.device = d.id;
    background.components.push_back(std::move(r));
  }
  return background.components.empty() || out.allocator.allocate(background, {}).has_value();
}

} // namespace

TEST_CASE("planner property: plans satisfy every constraint and exist iff brute force finds one",
          "[planner][random]") {
  int planned = 0;
  const std::uint32_t cases = 4000;
  for (std::uint32_t seed = 1; seed <= cases; ++seed) {
    const Case c = random_case(seed);
    const Built b = build(c);
    const auto result = make_plan(b.state, b.request, options_of(c));
    const bool exists = brute_force(c);
    planned += result ? 1 : 0;
    if (result) {
      // (a) a plan breaks no constraint and over-commits nothing.
      if (auto why = violation(c, b, *result))
        FAIL("the plan breaks a constraint\n"
             << describe(c) << "plan:\n"
             << describe(*result) << *why);
      if (!exists)
        FAIL("a plan where brute force finds none\n"
             << describe(c) << "plan:\n"
             << describe(*result));
    } else if (exists) {
      // (b) complete: no plan is missed.
      FAIL("no plan although brute force finds one\n" << describe(c) << to_string(result.error()));
    }
  }
  // Not vacuous: the generator yields both outcomes often.
  CHECK(planned > static_cast<int>(cases) / 10);
  CHECK(planned < static_cast<int>(cases) * 9 / 10);
}

TEST_CASE("planner property: ResourceAllocator is all or nothing and release round-trips",
          "[planner][random]") {
  const std::uint32_t cases = 2000;
  int allocated = 0, rejected = 0; // checked to the end, each way
  for (std::uint32_t seed = 100001; seed < 100001 + cases; ++seed) {
    const Case c = random_case(seed);
    const Built b = build(c);
    LoadedAllocator loaded;
    if (!load(loaded, c))
      FAIL("the background load does not fit\n" << describe(c));
    auto &allocator = loaded.allocator;
    const DomainState before = allocator.snapshot();
    const bool plannable = make_plan(before, b.request, options_of(c)).has_value();
    const auto result = allocator.allocate(b.request, options_of(c));
    if (result.has_value() != plannable)
      FAIL("allocate and make_plan disagree\n" << describe(c));
    if (!result) {
      // (c) a rejection reserves nothing.
      if (!rsca::test::same_load(allocator.snapshot(), before))
        FAIL("a rejected allocate changed the state\n"
             << describe(c) << "before:\n"
             << describe(before) << "after:\n"
             << describe(allocator.snapshot()));
      ++rejected;
      continue;
    }
    allocator.release(*result);
    if (!close_load(allocator.snapshot(), before))
      FAIL("allocate + release does not round-trip\n"
           << describe(c) << "plan:\n"
           << describe(*result) << "before:\n"
           << describe(before) << "after:\n"
           << describe(allocator.snapshot()));
    ++allocated;
  }
  // Not vacuous: every case was checked, and both outcomes often.
  INFO(allocated << " allocated, " << rejected << " rejected");
  CHECK(allocated + rejected == static_cast<int>(cases));
  CHECK(allocated > static_cast<int>(cases) / 10);
  CHECK(rejected > static_cast<int>(cases) / 10);
}

// Periodic components: what a plan commits is what gets deployed (cpu_tasks with the delivered
// priorities), so every CPU's committed task set must pass the same analysis that admitted it,
// and no delivered response time may be below what that analysis finds.
TEST_CASE("planner property: committed periodic task sets pass their own analysis",
          "[planner][random]") {
  const std::int64_t periods[] = {4, 5, 7, 10, 20, 50, 100};
  const std::uint32_t cases = 1000;
  int committed_plans = 0, task_sets = 0, responses = 0; // what was checked
  for (std::uint32_t seed = 200001; seed < 200001 + cases; ++seed) {
    std::mt19937 rng(seed);
    DomainState state;
    std::ostringstream text;
    text << "seed " << seed << "\n";
    const int devices = pick(rng, 1, 2);
    for (int d = 0; d < devices; ++d) {
      Device dev;
      dev.id = "n" + std::to_string(d) + ":GPP";
      dev.node = "n" + std::to_string(d);
      dev.kind = "gpp";
      dev.cpus = static_cast<unsigned>(pick(rng, 1, 2));
      dev.policy = chance(rng, 30) ? SchedulingPolicy::Edf : SchedulingPolicy::FixedPriority;
      dev.capacity[kCpuCapacity] = 100.0 * dev.cpus;
      text << "  device " << dev.id << " cpus " << dev.cpus << " " << to_string(dev.policy) << "\n";
      state[dev.id] = DeviceState{dev, {}};
    }
    auto pkg = softpkg_of("periodic", {ImplModel{"cpp", "", 0, 0}});
    PlanRequest request;
    const int components = pick(rng, 1, 5);
    for (int k = 0; k < components; ++k) {
      const std::int64_t t = periods[pick(rng, 0, 6)];
      const std::int64_t e = pick(rng, 1, static_cast<int>(std::max<std::int64_t>(1, t / 2)));
      ComponentRequest r;
      r.instance = "t" + std::to_string(k);
      r.softpkg = pkg.get();
      r.timing.emplace();
      r.timing->period = Duration{std::chrono::milliseconds{t}};
      r.timing->execution_time = Duration{std::chrono::milliseconds{e}};
      text << "  component " << r.instance << " C=" << e << "ms T=" << t << "ms\n";
      request.components.push_back(std::move(r));
    }
    PlanOptions options;
    options.strategy = chance(rng, 50) ? Strategy::Pack : Strategy::Spread;
    const auto result = make_plan(state, request, options);
    if (!result)
      continue;
    DomainState committed = state;
    commit(committed, *result);
    ++committed_plans;
    for (const auto &[id, s] : committed)
      for (std::size_t cpu = 0; cpu < s.load.cpu_tasks.size(); ++cpu) {
        if (s.load.cpu_tasks[cpu].empty())
          continue;
        ++task_sets;
        const auto verdict = analyse(s.load.cpu_tasks[cpu], s.device.policy);
        if (!verdict.schedulable)
          FAIL("the committed set of " << id << " cpu " << cpu
                                       << " fails its analysis: " << verdict.reason << "\n"
                                       << text.str());
        for (const auto &v : verdict.tasks)
          for (const auto &p : result->placements) {
            if (p.instance != v.id || !p.schedule)
              continue;
            ++responses;
            if (p.schedule->response_time < v.response_time)
              FAIL(p.instance
                   << " delivered response "
                   << std::chrono::duration_cast<std::chrono::microseconds>(
                          p.schedule->response_time)
                          .count()
                   << "us, the committed set's analysis finds "
                   << std::chrono::duration_cast<std::chrono::microseconds>(v.response_time).count()
                   << "us\n"
                   << text.str());
          }
      }
  }
  // Not vacuous: most cases commit a plan, and every delivered response time was compared.
  INFO(committed_plans << " plans committed, " << task_sets << " task sets analysed, " << responses
                       << " response times compared");
  CHECK(committed_plans > static_cast<int>(cases) / 2);
  CHECK(task_sets >= committed_plans);
  CHECK(responses >= committed_plans);
}
