// The planner's private parts, shared by its files: planner_rules.cpp (whether an implementation
// can run on a device at all, capacities, timing admission on a device's CPUs), planner_search.cpp
// (the depth-first search that places the components with those rules) and planner.cpp (the
// public functions: tasks and demands of an implementation, make_plan, commit and release). The
// rules are pure functions of one device's state, the search owns the working copy it tries them
// on. Nothing outside allocator/ includes this header.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <tl/expected.hpp>

#include "allocator/planner.hpp"

namespace rsca::allocator::detail {

using profile::Implementation;
using profile::ResolvedImplementation;

inline Nanos nanos_of(const Duration &d) {
  return std::chrono::duration_cast<Nanos>(*d.value);
}
inline bool finite(const std::optional<Duration> &d) {
  return d && !d->infinite();
}

// ---- static checks (planner_rules.cpp): whether an implementation can run on a device at all --

// os, processor and the implementation's matching property dependencies.
std::optional<std::string> implementation_mismatch(const Implementation &impl,
                                                   const Device &device);
// Whether every softpkg dependency of `impl` has an implementation that fits the same device
// (recursively, as SCA requires: dependencies load where the component loads).
std::optional<std::string> dependency_mismatch(const ResolvedImplementation &impl,
                                               const Device &device, int depth = 0);
// SCA devicerequires / deployerrequires: a component that requires goes only to a device that
// offers, and a device that offers takes only components that require exactly what it offers.
std::optional<std::string> requires_mismatch(const ComponentRequest &c, const Device &device);

// ---- capacities (planner_rules.cpp)
// ---------------------------------------------------------------

std::optional<std::string> capacity_shortfall(const std::map<std::string, double> &demand,
                                              const DeviceState &state);
// How full a device is, 0 to 1: its fullest finite capacity.
double load_of(const DeviceState &state);
// Adds (sign +1) or takes back (sign -1) `amounts`, never below zero.
void add(std::map<std::string, double> &to, const std::map<std::string, double> &amounts,
         double sign);
// What a usesdevice reserves (its external requirements) and whether a device matches the rest.
std::map<std::string, double> uses_demand(const profile::UsesDevice &uses, const Device &device);
std::optional<std::string> uses_mismatch(const profile::UsesDevice &uses, const DeviceState &state);

// ---- timing (planner_rules.cpp) -----------------------------------------------------------------

// Tries the task on the device's CPUs (most loaded first when packing, least loaded when
// spreading); the CPU and the analysis of its task set with the task added, or why none fits.
tl::expected<std::pair<unsigned, Schedulability>, std::string>
admit(const Task &task, const DeviceState &state, Strategy strategy);
Schedule schedule_of(const Task &task, unsigned cpu, const Schedulability &verdict,
                     SchedulingPolicy policy);

// ---- the search (planner_search.cpp)
// --------------------------------------------------------------

// make_plan's work: a plan for `request` on `state`, or why there is none.
tl::expected<Plan, std::vector<Rejection>>
search(const DomainState &state, const PlanRequest &request, const PlanOptions &options);

} // namespace rsca::allocator::detail
