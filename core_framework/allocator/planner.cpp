// The planner's public functions (allocator/planner.hpp): the task and the demand of an
// implementation, make_plan (the search itself is in planner_search.cpp, its rules in
// planner_rules.cpp), commit and release of a plan on a domain state, and the request a
// resolved application makes.
#include "allocator/planner.hpp"
#include "allocator/planner_impl.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <string_view>

#include <fmt/format.h>

namespace rsca::allocator {

using namespace detail;

namespace {

constexpr double kMiB = 1024.0 * 1024.0;

void apply_plan(DomainState &state, const Plan &plan, double sign) {
  auto device = [&](const std::string &id) -> DeviceState * {
    auto it = state.find(id);
    return it == state.end() ? nullptr : &it->second; // a node gone takes its allocations along
  };
  for (const auto &p : plan.placements) {
    if (auto *s = device(p.device)) {
      add(s->load.allocated, p.demand, sign);
      if (p.task && p.schedule) {
        if (s->load.cpu_tasks.size() <= p.schedule->cpu)
          s->load.cpu_tasks.resize(p.schedule->cpu + 1);
        auto &tasks = s->load.cpu_tasks[p.schedule->cpu];
        if (sign > 0) {
          tasks.push_back(*p.task);
        } else {
          // Equal tasks are interchangeable for the analysis: remove any one of them.
          auto it = std::find_if(tasks.begin(), tasks.end(), [&](const Task &t) {
            return t.id == p.task->id && t.period == p.task->period &&
                   t.execution == p.task->execution && t.deadline == p.task->deadline;
          });
          if (it != tasks.end())
            tasks.erase(it);
        }
      }
    }
    for (const auto &used : p.used_devices)
      if (auto *s = device(used.device))
        add(s->load.allocated, used.demand, sign);
  }
  for (const auto &used : plan.application_devices)
    if (auto *s = device(used.device))
      add(s->load.allocated, used.demand, sign);
}

} // namespace

std::string_view to_string(Strategy strategy) {
  return strategy == Strategy::Pack ? "pack" : "spread";
}

std::optional<Strategy> parse_strategy(std::string_view text) {
  if (text == "pack")
    return Strategy::Pack;
  if (text == "spread")
    return Strategy::Spread;
  return std::nullopt;
}

std::string to_string(const std::vector<Rejection> &rejections) {
  std::string out;
  for (const auto &r : rejections) {
    out += fmt::format("{}{}: cannot be placed", out.empty() ? "" : "\n", r.instance);
    for (const auto &reason : r.reasons)
      out += fmt::format("\n  {}", reason);
  }
  return out;
}

std::optional<Task> task_of(const std::string &instance, const Implementation &implementation,
                            const std::optional<profile::Timing> &timing) {
  const auto &demand = implementation.resource_demand;
  std::optional<Duration> period = timing && finite(timing->period) ? timing->period : std::nullopt;
  if (!period && demand && finite(demand->period))
    period = demand->period;
  if (!period || nanos_of(*period).count() <= 0)
    return std::nullopt;
  const Nanos t = nanos_of(*period);
  Nanos c{0};
  if (timing && finite(timing->execution_time))
    c = nanos_of(*timing->execution_time);
  else if (demand && finite(demand->execution_time))
    c = nanos_of(*demand->execution_time);
  else if (demand && demand->utilization)
    c = Nanos(static_cast<Nanos::rep>(
        std::llround(*demand->utilization * static_cast<double>(t.count()))));
  if (c.count() <= 0)
    return std::nullopt;
  const Nanos d = timing && finite(timing->deadline) ? nanos_of(*timing->deadline) : t;
  return Task{instance, t, c, d, timing ? timing->priority : std::nullopt};
}

std::map<std::string, double> demand_of(const Implementation &implementation,
                                        const std::optional<profile::Timing> &timing) {
  std::map<std::string, double> demand;
  if (auto task = task_of("", implementation, timing))
    demand[kCpuCapacity] = 100.0 * static_cast<double>(task->execution.count()) /
                           static_cast<double>(task->period.count());
  if (!implementation.resource_demand)
    return demand;
  const auto &d = *implementation.resource_demand;
  if (d.utilization && demand.count(kCpuCapacity) == 0)
    demand[kCpuCapacity] = *d.utilization * 100.0;
  if (d.memory_bytes)
    demand[kMemCapacity] = static_cast<double>(*d.memory_bytes) / kMiB;
  if (d.bandwidth_bps)
    demand[kNetCapacity] = *d.bandwidth_bps / 1e6;
  return demand;
}

tl::expected<Plan, std::vector<Rejection>>
make_plan(const DomainState &state, const PlanRequest &request, const PlanOptions &options) {
  return search(state, request, options);
}

void commit(DomainState &state, const Plan &plan) {
  apply_plan(state, plan, +1);
}

void release(DomainState &state, const Plan &plan) {
  apply_plan(state, plan, -1);
}

std::optional<std::string>
unknown_assignment(const profile::ResolvedApplication &application,
                   const std::map<std::string, std::string> &assignments) {
  std::set<std::string_view> ids;
  for (const auto &placement : application.sad->placements)
    for (const auto &ci : placement.instantiations)
      ids.insert(ci.id);
  for (const auto &[id, device] : assignments)
    if (!ids.contains(id))
      return id;
  return std::nullopt;
}

PlanRequest plan_request_of(const profile::ResolvedApplication &application,
                            const std::map<std::string, std::string> &assignments) {
  PlanRequest request;
  const auto &sad = *application.sad;
  std::map<std::string, double> bandwidth; // Mbps each instance declares
  for (const auto &placement : sad.placements) {
    const auto *pkg = application.softpkg_of(placement);
    for (const auto &ci : placement.instantiations) {
      ComponentRequest c{
          ci.id, pkg, std::nullopt, placement.host_collocation, ci.device_requires, ci.timing};
      if (auto it = assignments.find(ci.id); it != assignments.end())
        c.device = it->second;
      double mbps = 0;
      if (pkg != nullptr)
        for (const auto &impl : pkg->implementations)
          if (impl.implementation->resource_demand &&
              impl.implementation->resource_demand->bandwidth_bps)
            mbps = std::max(mbps, *impl.implementation->resource_demand->bandwidth_bps / 1e6);
      bandwidth[ci.id] = mbps;
      request.components.push_back(std::move(c));
    }
  }
  for (const auto &connection : sad.connections) {
    using Kind = profile::EndpointTarget::Kind;
    if (connection.uses.target.kind != Kind::ComponentInstantiation ||
        connection.provides.target.kind != Kind::ComponentInstantiation)
      continue;
    const auto &uses = connection.uses.target.refid;
    const auto &provides = connection.provides.target.refid;
    if (uses.empty() || provides.empty() || uses == provides)
      continue;
    request.affinities.push_back({uses, provides, 1.0 + bandwidth[uses]});
  }
  for (const auto &hc : sad.host_collocations) {
    if (!hc.cpu_cores && hc.uses_device_refs.empty())
      continue;
    request.collocations.push_back(
        {hc.key, hc.cpu_cores.value_or(0.0) * 100.0, hc.uses_device_refs});
  }
  request.uses_devices = sad.uses_device_dependencies;
  request.latency_paths = sad.latency_paths;
  return request;
}

} // namespace rsca::allocator
