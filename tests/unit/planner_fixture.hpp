// Builders of hand-made devices, software packages and requests for the planner's tests, and
// helpers that read a plan or a rejection; shared by planner_test.cpp (what one device accepts),
// planner_placement_test.cpp (where components go together), planner_timing_test.cpp and
// planner_strategy_test.cpp.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <catch2/catch.hpp>

#include "allocator/planner.hpp"

namespace rsca::test {

using namespace rsca::allocator;
using std::chrono::milliseconds;

using PlanResult = tl::expected<Plan, std::vector<Rejection>>;
using PkgPtr = std::shared_ptr<const profile::ResolvedSoftPkg>;

// ---- fixture builders ---------------------------------------------------------------------------

inline profile::SimpleRef ref(std::string refid, std::string value) {
  profile::SimpleRef r;
  r.refid = std::move(refid);
  r.value = std::move(value);
  return r;
}

// One implementation of a package and the softpkg dependencies it resolves to (these live in
// ResolvedImplementation, not in profile::Implementation).
struct ImplSpec {
  profile::Implementation impl;
  std::vector<profile::ResolvedDependency> dependencies;

  explicit ImplSpec(std::string id) { impl.id = std::move(id); }
  ImplSpec &os(std::string name) {
    impl.os.push_back({std::move(name), ""});
    return *this;
  }
  ImplSpec &processor(std::string name) {
    impl.processors.push_back(std::move(name));
    return *this;
  }
  // Fraction of one CPU: the planner demands 100 * u percent of cpu_capacity.
  ImplSpec &utilization(double u) {
    demand().utilization = u;
    return *this;
  }
  ImplSpec &memory_mib(std::uint64_t mib) {
    demand().memory_bytes = mib * 1024 * 1024;
    return *this;
  }
  ImplSpec &needs(std::string refid, std::string value) {
    impl.property_dependencies.push_back({"matching", ref(std::move(refid), std::move(value))});
    return *this;
  }
  ImplSpec &uses(profile::UsesDevice uses) {
    impl.uses_devices.push_back(std::move(uses));
    return *this;
  }
  ImplSpec &depends_on(PkgPtr pkg, std::optional<std::string> implref = std::nullopt) {
    dependencies.push_back({std::move(pkg), std::move(implref)});
    return *this;
  }

private:
  profile::ResourceDemand &demand() {
    if (!impl.resource_demand)
      impl.resource_demand.emplace();
    return *impl.resource_demand;
  }
};

// A resolved package whose ResolvedImplementations point into the SoftPkg it shares ownership
// of, so the package stays valid as long as the returned pointer lives.
inline PkgPtr softpkg(const std::string &name, const std::vector<ImplSpec> &impls) {
  auto spd = std::make_shared<profile::SoftPkg>();
  spd->id = name;
  spd->name = name;
  for (const auto &i : impls)
    spd->implementations.push_back(i.impl);
  auto pkg = std::make_shared<profile::ResolvedSoftPkg>();
  pkg->spd_path = name + ".spd.xml";
  pkg->spd = spd;
  for (std::size_t k = 0; k < impls.size(); ++k)
    pkg->implementations.push_back({&spd->implementations[k], nullptr, impls[k].dependencies});
  return pkg;
}

// A GPP with os_name / processor_name matching properties and cpu / mem capacities.
inline Device gpp_device(std::string id, std::string node, double cpu = 100, double mem = 1024,
                         std::string os = "Linux", std::string processor = "x86_64") {
  Device d;
  d.id = std::move(id);
  d.node = std::move(node);
  d.kind = "gpp";
  d.properties.push_back({"os_name", "os_name", std::move(os), profile::Action::Eq});
  d.properties.push_back(
      {"processor_name", "processor_name", std::move(processor), profile::Action::Eq});
  d.capacity[kCpuCapacity] = cpu;
  d.capacity[kMemCapacity] = mem;
  return d;
}

// A device components use through usesdevice (not a GPP).
inline Device peripheral(std::string id, std::string node, std::vector<MatchingProperty> properties,
                         std::map<std::string, double> capacity) {
  Device d;
  d.id = std::move(id);
  d.node = std::move(node);
  d.kind = "device";
  d.properties = std::move(properties);
  d.capacity = std::move(capacity);
  return d;
}

inline DomainState domain_state(const std::vector<Device> &devices) {
  DomainState state;
  for (const auto &d : devices)
    state[d.id] = DeviceState{d, {}};
  return state;
}

inline ComponentRequest component_request(std::string instance, const PkgPtr &pkg) {
  ComponentRequest c;
  c.instance = std::move(instance);
  c.softpkg = pkg.get();
  return c;
}

inline ComponentRequest periodic(std::string instance, const PkgPtr &pkg, std::int64_t period_ms,
                                 std::int64_t execution_ms) {
  ComponentRequest c = component_request(std::move(instance), pkg);
  c.timing.emplace();
  c.timing->period = Duration{milliseconds{period_ms}};
  c.timing->execution_time = Duration{milliseconds{execution_ms}};
  return c;
}

inline profile::UsesDevice uses_device(std::string id,
                                       std::vector<profile::PropertyRef> requirements) {
  profile::UsesDevice u;
  u.id = std::move(id);
  u.type = "device";
  u.requirements = std::move(requirements);
  return u;
}

inline profile::LatencyPath latency_path(std::string id, std::int64_t bound_ms,
                                         std::vector<std::string> components) {
  profile::LatencyPath p;
  p.id = std::move(id);
  p.bound = Duration{milliseconds{bound_ms}};
  p.components = std::move(components);
  return p;
}

inline PlanRequest request_of(std::vector<ComponentRequest> components) {
  PlanRequest r;
  r.components = std::move(components);
  return r;
}

inline PlanOptions with(Strategy strategy) {
  PlanOptions o;
  o.strategy = strategy;
  return o;
}

// ---- result helpers -----------------------------------------------------------------------------

inline std::string why(const PlanResult &result) {
  return result ? std::string("(planned)") : to_string(result.error());
}

inline Plan require_plan(const PlanResult &result) {
  INFO(why(result));
  REQUIRE(result.has_value());
  return *result;
}

inline std::vector<Rejection> require_rejection(const PlanResult &result) {
  REQUIRE_FALSE(result.has_value());
  return result.error();
}

inline const Placement &placement_of(const Plan &plan, const std::string &instance) {
  for (const auto &p : plan.placements)
    if (p.instance == instance)
      return p;
  FAIL("no placement for " << instance);
  throw std::logic_error("unreachable");
}

inline std::string device_of(const Plan &plan, const std::string &instance) {
  return placement_of(plan, instance).device;
}

inline std::string implementation_of(const Plan &plan, const std::string &instance) {
  return placement_of(plan, instance).implementation->id;
}

inline double allocated(const DomainState &state, const std::string &device,
                        const std::string &capacity) {
  const auto &a = state.at(device).load.allocated;
  auto it = a.find(capacity);
  return it == a.end() ? 0.0 : it->second;
}

} // namespace rsca::test
