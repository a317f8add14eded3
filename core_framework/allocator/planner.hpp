// The placement planner: for an application's components, finds an implementation and a device
// for each that satisfies every constraint (os, processor, softpkg dependencies, matching
// properties, capacities, host collocation, devicerequires, explicit assignment, usesdevice,
// timing admission per CPU, end-to-end latency bounds), or says per component why none does.
//
// A pure function of the domain state and the request: deterministic, no locking, no side
// effects. The search is depth first over components, most constrained first, with the
// strategy's device order as value order; it backtracks, so it finds a plan whenever one exists
// within its budget of tries.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <tl/expected.hpp>

#include "allocator/device.hpp"
#include "allocator/schedulability.hpp"
#include "profile/profile_loader.hpp"

namespace rsca::allocator {

// What is allocated on one device, and the periodic components each of its CPUs runs.
struct DeviceLoad {
  std::map<std::string, double> allocated;
  std::vector<std::vector<Task>> cpu_tasks; // one task set per CPU (empty: none yet)

  friend bool operator==(const DeviceLoad &, const DeviceLoad &) = default;
};

struct DeviceState {
  Device device;
  DeviceLoad load;
};
using DomainState = std::map<std::string, DeviceState>; // by device id: deterministic order

enum class Strategy : std::uint8_t {
  Pack,   // fewest devices: fill the most loaded device that fits
  Spread, // balance load: the least loaded device that fits, partners together up to a fair share
};
std::string_view to_string(Strategy strategy);
std::optional<Strategy> parse_strategy(std::string_view text);

// One component instance to place.
struct ComponentRequest {
  std::string instance;
  const profile::ResolvedSoftPkg *softpkg = nullptr;
  std::optional<std::string> device;                 // explicit assignment (rsca launch --assign)
  std::string collocation;                           // hostcollocation id; empty for none
  std::vector<profile::PropertyRef> device_requires; // the SAD's devicerequires
  std::optional<profile::Timing> timing;             // the SAD's timing, over the SPD's demand
};

// Components that exchange data: the planner prefers one host for them.
struct Affinity {
  std::string a;
  std::string b;
  double weight = 1; // heavier pairs win over the strategy
};

// What a host collocation asks of its host as a whole (REDHAWK 2.2's hostcollocation children).
struct CollocationRequest {
  std::string id; // as ComponentRequest::collocation names it
  // A floor on the CPU its components are charged together, in cpu_capacity units (percent of
  // one core): the members' own demand, topped up to this by the last member placed.
  double cpu_reservation = 0;
  std::vector<std::string> uses_devices; // SAD usesdevice ids whose devices must be on its host
};

struct PlanRequest {
  std::vector<ComponentRequest> components;
  std::vector<CollocationRequest> collocations;
  std::vector<Affinity> affinities;
  std::vector<profile::UsesDevice> uses_devices; // the SAD's own usesdevice dependencies
  std::vector<profile::LatencyPath> latency_paths;
};

// What admission decided for a periodic component, delivered to it at launch.
struct Schedule {
  unsigned cpu = 0;
  SchedulingPolicy policy = SchedulingPolicy::FixedPriority;
  std::uint32_t priority = 0;
  Nanos period{0};
  Nanos budget{0}; // execution time per period
  Nanos deadline{0};
  Nanos response_time{0}; // worst case, from the analysis
};

// A device a component (or the application) uses, and the capacity reserved there.
struct UsedDevice {
  std::string uses_id; // the usesdevice id
  std::string device;
  std::map<std::string, double> demand;
};

struct Placement {
  std::string instance;
  std::string device;
  std::string node;
  const profile::Implementation *implementation = nullptr;
  std::map<std::string, double> demand; // reserved on the device
  std::optional<Task> task;             // periodic components: the task as the profiles give it
  std::optional<Schedule> schedule;     // and what admission decided for it
  std::vector<UsedDevice> used_devices;
};

// Names one reservation of the ResourceAllocator (one allocate); 0 names none.
using AllocationId = std::uint64_t;

struct Plan {
  std::vector<Placement> placements;
  std::vector<UsedDevice> application_devices; // the SAD's own usesdevice
  std::vector<std::string> notes;              // what was not checked, and why
  // The reservation this plan was committed as by ResourceAllocator::allocate; 0 for a plan
  // that reserved nothing (make_plan, ResourceAllocator::plan).
  AllocationId allocation = 0;
};

// Why a request could not be placed: per component, each device and what failed there.
struct Rejection {
  std::string instance;
  std::vector<std::string> reasons; // "node2:GPP_1 (cpp): mem_capacity needs 512 MiB, 200 MiB free"
};
std::string to_string(const std::vector<Rejection> &rejections);

struct PlanOptions {
  Strategy strategy = Strategy::Pack;
  std::size_t budget = 200000; // placements tried before the search gives up
};

// The capacity an implementation demands, from its RSCA resource demand (none declared: zero).
std::map<std::string, double> demand_of(const profile::Implementation &implementation,
                                        const std::optional<profile::Timing> &timing = {});
// The periodic task a component is, when its period and execution time are known.
std::optional<Task> task_of(const std::string &instance,
                            const profile::Implementation &implementation,
                            const std::optional<profile::Timing> &timing);

tl::expected<Plan, std::vector<Rejection>>
make_plan(const DomainState &state, const PlanRequest &request, const PlanOptions &options = {});

// Reserves (commit) or frees (release) what a plan allocates.
void commit(DomainState &state, const Plan &plan);
void release(DomainState &state, const Plan &plan);

// The plan request for an application: every instantiation, with its timing, collocation and
// devicerequires; connections as affinities; `assignments` are explicit devices by instance.
PlanRequest plan_request_of(const profile::ResolvedApplication &application,
                            const std::map<std::string, std::string> &assignments = {});
// The first of `assignments` that names no instantiation of `application`: such an entry would be
// ignored, and a request of half a million of them was kept whole (issue 37, defect 8).
std::optional<std::string>
unknown_assignment(const profile::ResolvedApplication &application,
                   const std::map<std::string, std::string> &assignments);

} // namespace rsca::allocator
