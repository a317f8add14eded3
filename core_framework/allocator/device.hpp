// A device as the ResourceAllocator sees it: its matching allocation properties, its capacities,
// and how its CPUs schedule periodic components. Built from a node's announcement (a running
// domain) or from a DCD and its device packages (offline planning), by the same rules.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "allocator/schedulability.hpp"
#include "profile/profile_loader.hpp"
#include "profile/property_value.hpp"

namespace rsca::allocator {

// Capacity names, as the GPP's PRF declares them.
inline constexpr const char *kCpuCapacity = "cpu_capacity";  // percent of one core
inline constexpr const char *kMemCapacity = "mem_capacity";  // MiB
inline constexpr const char *kNetCapacity = "nic_bandwidth"; // Mbps

// A matching allocation property: a requirement is compared with the device's value by the
// property's action, the device's value on the left (SCA: "device_value action required").
struct MatchingProperty {
  std::string id;
  std::string name;
  std::string value;
  profile::Action action = profile::Action::Eq;
};

struct Device {
  std::string id;   // e.g. "node1:GPP_1"
  std::string node; // its node's name
  std::string kind; // "gpp" executes components; any other is used through usesdevice
  std::vector<MatchingProperty> properties;
  // Total capacities by name. A capacity whose amount is not known (offline, when neither the
  // PRF nor the DCD gives it) is infinite: not checked, and the plan says so.
  std::map<std::string, double> capacity;
  std::map<std::string, std::string> deployer_requires; // the DCD's deployerrequires, id -> value
  SchedulingPolicy policy = SchedulingPolicy::FixedPriority;
  unsigned cpus = 1; // timing admission is partitioned: one task set per CPU

  // The matching property with that id or name, or nullptr.
  const MatchingProperty *find_property(std::string_view id_or_name) const;
  std::string property_value(std::string_view id_or_name) const;
};

// Whether the device's property satisfies `required` under its action: numbers compare as
// numbers, anything else as text (only eq and ne apply to text).
bool satisfies(const MatchingProperty &property, const std::string &required);

// How much of a capacity, for messages: "512 MiB", "25.0% CPU", "unknown".
std::string describe_amount(const std::string &capacity, double amount);

// What a node daemon announces of a device's allocation properties, from the device's PRF:
// [{"id", "name", "action"}] for every simple property of kind allocation.
nlohmann::json allocation_properties_json(const profile::ResolvedSoftPkg &device_pkg);

// A device from one entry of a node's announcement ({"id", "kind", "properties", "capacity",
// "allocation", "deployerrequires", ...}).
Device device_from_announcement(const std::string &node, const nlohmann::json &entry);

// The devices a DCD declares, described from their PRFs and the DCD's overrides alone (nothing
// is measured): what offline planning (`rsca plan --node DCD`) places on.
std::vector<Device> devices_of_node(const profile::ResolvedNode &node);
// One device of a DCD, described the same way.
Device describe_offline(const std::string &node, const std::string &id,
                        const profile::ComponentInstantiation &ci,
                        const profile::ResolvedSoftPkg &pkg);

} // namespace rsca::allocator
