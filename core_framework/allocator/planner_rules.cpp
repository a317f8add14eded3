// The planner's rules for one device: whether an implementation can run on it at all (os,
// processor, matching properties, softpkg dependencies, devicerequires/deployerrequires), whether
// its capacities hold a demand, and timing admission on its CPUs. Each is a pure function of the
// device's state that says why when the answer is no; the search (planner_search.cpp) tries
// them on its working copy of the domain.
#include "allocator/planner_impl.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace rsca::allocator::detail {

constexpr double kEpsilon = 1e-9;
constexpr int kMaxDependencyDepth = profile::kMaxSoftpkgDependencyDepth;

// ---- static checks: whether an implementation can run on a device at all ----------------------

namespace {

std::optional<std::string> os_processor_mismatch(const Implementation &impl, const Device &device) {
  const std::string os = device.property_value("os_name");
  if (!impl.os.empty() &&
      std::none_of(impl.os.begin(), impl.os.end(), [&](const auto &o) { return o.name == os; })) {
    std::vector<std::string> wanted;
    for (const auto &o : impl.os)
      wanted.push_back(o.name);
    return fmt::format("os_name is {}, implementation {} needs {}", os.empty() ? "unknown" : os,
                       impl.id, fmt::join(wanted, " or "));
  }
  const std::string processor = device.property_value("processor_name");
  if (!impl.processors.empty() &&
      std::find(impl.processors.begin(), impl.processors.end(), processor) == impl.processors.end())
    return fmt::format("processor_name is {}, implementation {} needs {}",
                       processor.empty() ? "unknown" : processor, impl.id,
                       fmt::join(impl.processors, " or "));
  return std::nullopt;
}

// A requirement (propertyref / simpleref) against the device's matching property of that id.
std::optional<std::string> requirement_mismatch(const profile::PropertyRef &ref,
                                                const Device &device) {
  const auto *simple = std::get_if<profile::SimpleRef>(&ref);
  if (simple == nullptr)
    return std::nullopt; // structured requirements are capacities of their own kind: not matched
  if (device.capacity.count(simple->refid) != 0)
    return std::nullopt; // a capacity, allocated rather than matched
  const auto *property = device.find_property(simple->refid);
  if (property == nullptr)
    return fmt::format("has no allocation property {}", simple->refid);
  if (!satisfies(*property, simple->value))
    return fmt::format("{} is {}, needs {} {}", property->name,
                       property->value.empty() ? "unknown" : property->value,
                       profile::to_string(property->action), simple->value);
  return std::nullopt;
}

std::optional<std::string> property_dependency_mismatch(const Implementation &impl,
                                                        const Device &device) {
  for (const auto &dep : impl.property_dependencies)
    if (auto why = requirement_mismatch(dep.requirement, device))
      return fmt::format("implementation {} depends on a device that {}", impl.id, *why);
  return std::nullopt;
}

} // namespace

std::optional<std::string> implementation_mismatch(const Implementation &impl,
                                                   const Device &device) {
  if (auto why = os_processor_mismatch(impl, device))
    return why;
  return property_dependency_mismatch(impl, device);
}

// Whether every softpkg dependency of `impl` has an implementation that fits the same device
// (recursively, as SCA requires: dependencies load where the component loads).
std::optional<std::string> dependency_mismatch(const ResolvedImplementation &impl,
                                               const Device &device, int depth) {
  if (depth > kMaxDependencyDepth)
    return "softpkg dependencies nest too deep";
  for (const auto &dep : impl.dependencies) {
    std::string why = "no implementation";
    const bool fits =
        std::any_of(dep.softpkg->implementations.begin(), dep.softpkg->implementations.end(),
                    [&](const ResolvedImplementation &candidate) {
                      if (dep.implref && candidate.implementation->id != *dep.implref)
                        return false;
                      auto m = implementation_mismatch(*candidate.implementation, device);
                      if (!m)
                        m = dependency_mismatch(candidate, device, depth + 1);
                      if (m)
                        why = *m;
                      return !m.has_value();
                    });
    if (!fits)
      return fmt::format("dependency {}: {}", dep.softpkg->spd->name, why);
  }
  return std::nullopt;
}

// SCA devicerequires / deployerrequires: a component that requires goes only to a device that
// offers, and a device that offers takes only components that require exactly what it offers.
std::optional<std::string> requires_mismatch(const ComponentRequest &c, const Device &device) {
  std::map<std::string, std::string> wanted;
  for (const auto &ref : c.device_requires)
    if (const auto *simple = std::get_if<profile::SimpleRef>(&ref))
      wanted[simple->refid] = simple->value;
  for (const auto &[id, value] : wanted) {
    auto it = device.deployer_requires.find(id);
    if (it == device.deployer_requires.end() || it->second != value)
      return fmt::format("devicerequires {}={}, the device's deployerrequires do not offer it", id,
                         value);
  }
  for (const auto &[id, value] : device.deployer_requires) {
    auto it = wanted.find(id);
    if (it == wanted.end() || it->second != value)
      return fmt::format("deployerrequires {}={}: the device takes only components that require it",
                         id, value);
  }
  return std::nullopt;
}

// ---- capacities ---------------------------------------------------------------------------------

namespace {

double free_of(const DeviceState &state, const std::string &capacity) {
  auto total = state.device.capacity.find(capacity);
  if (total == state.device.capacity.end())
    return 0;
  auto used = state.load.allocated.find(capacity);
  return total->second - (used == state.load.allocated.end() ? 0.0 : used->second);
}

} // namespace

std::optional<std::string> capacity_shortfall(const std::map<std::string, double> &demand,
                                              const DeviceState &state) {
  for (const auto &[name, amount] : demand) {
    if (amount <= 0)
      continue;
    if (state.device.capacity.count(name) == 0)
      return fmt::format("{}: the device has no {} capacity", name, name);
    const double free = free_of(state, name);
    if (amount > free + kEpsilon)
      return fmt::format("{} needs {}, {} free", name, describe_amount(name, amount),
                         describe_amount(name, std::max(0.0, free)));
  }
  return std::nullopt;
}

// How full a device is, 0 to 1: its fullest finite capacity.
double load_of(const DeviceState &state) {
  double load = 0;
  for (const auto &[name, total] : state.device.capacity)
    if (std::isfinite(total) && total > 0)
      load = std::max(load, 1.0 - free_of(state, name) / total);
  return load;
}

void add(std::map<std::string, double> &to, const std::map<std::string, double> &amounts,
         double sign) {
  for (const auto &[name, amount] : amounts) {
    double &v = to[name];
    v = std::max(0.0, v + sign * amount);
  }
}

// What a usesdevice reserves (its external requirements) and whether a device matches the rest.
std::map<std::string, double> uses_demand(const profile::UsesDevice &uses, const Device &device) {
  std::map<std::string, double> demand;
  for (const auto &ref : uses.requirements) {
    const auto *simple = std::get_if<profile::SimpleRef>(&ref);
    if (simple == nullptr)
      continue;
    auto capacity = device.capacity.find(simple->refid);
    if (capacity == device.capacity.end()) {
      const auto *p = device.find_property(simple->refid);
      if (p == nullptr || p->id == p->name)
        continue;
      capacity = device.capacity.find(p->name);
      if (capacity == device.capacity.end())
        continue;
    }
    try {
      demand[capacity->first] = std::stod(simple->value);
    } catch (const std::exception &) {
      demand[capacity->first] = 0;
    }
  }
  return demand;
}

std::optional<std::string> uses_mismatch(const profile::UsesDevice &uses,
                                         const DeviceState &state) {
  for (const auto &ref : uses.requirements)
    if (auto why = requirement_mismatch(ref, state.device))
      return why;
  return capacity_shortfall(uses_demand(uses, state.device), state);
}

// ---- timing -------------------------------------------------------------------------------------

// Tries the task on the device's CPUs (most loaded first when packing, least loaded when
// spreading); the CPU and the analysis of its task set with the task added, or why none fits.
tl::expected<std::pair<unsigned, Schedulability>, std::string>
admit(const Task &task, const DeviceState &state, Strategy strategy) {
  const unsigned cpus = std::max(1u, state.device.cpus);
  std::vector<std::pair<double, unsigned>> order;
  for (unsigned cpu = 0; cpu < cpus; ++cpu) {
    const double u =
        cpu < state.load.cpu_tasks.size() ? utilization(state.load.cpu_tasks[cpu]) : 0.0;
    order.emplace_back(strategy == Strategy::Pack ? -u : u, cpu);
  }
  std::sort(order.begin(), order.end());
  std::string first_reason;
  for (const auto &[key, cpu] : order) {
    std::vector<Task> tasks =
        cpu < state.load.cpu_tasks.size() ? state.load.cpu_tasks[cpu] : std::vector<Task>{};
    tasks.push_back(task);
    auto verdict = analyse(tasks, state.device.policy);
    if (verdict.schedulable)
      return std::pair{cpu, std::move(verdict)};
    if (first_reason.empty())
      first_reason =
          fmt::format("cpu {} ({}): {}", cpu, to_string(state.device.policy), verdict.reason);
  }
  return tl::unexpected(fmt::format("timing admission failed on every CPU; {}", first_reason));
}

Schedule schedule_of(const Task &task, unsigned cpu, const Schedulability &verdict,
                     SchedulingPolicy policy) {
  Schedule s{cpu, policy, 0, task.period, task.execution, task.deadline, task.deadline};
  for (const auto &v : verdict.tasks)
    if (v.id == task.id) {
      s.priority = v.priority;
      s.response_time = v.response_time;
    }
  return s;
}

} // namespace rsca::allocator::detail
