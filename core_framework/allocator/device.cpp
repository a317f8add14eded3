#include "allocator/device.hpp"

#include <charconv>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "profile/property_binding.hpp"

namespace rsca::allocator {
namespace {

using nlohmann::json;

constexpr double kUnknown = std::numeric_limits<double>::infinity();

std::optional<double> as_number(std::string_view text) {
  double value = 0;
  const auto *end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || text.empty())
    return std::nullopt;
  return value;
}

template <typename T>
int compare(const T &a, const T &b) {
  return a < b ? -1 : (b < a ? 1 : 0);
}

std::string text_of(const json &value) {
  return value.is_string() ? value.get<std::string>() : value.dump();
}

std::optional<profile::Action> parse_action(std::string_view text) {
  for (auto a : {profile::Action::Eq, profile::Action::Ne, profile::Action::Gt, profile::Action::Lt,
                 profile::Action::Ge, profile::Action::Le, profile::Action::External})
    if (profile::to_string(a) == text)
      return a;
  return std::nullopt;
}

// The CPUs timing admission partitions over: whole cores of the CPU capacity, else nbCores.
unsigned cpus_of(const Device &device, std::optional<double> cores_property) {
  auto cpu = device.capacity.find(kCpuCapacity);
  if (cpu != device.capacity.end() && std::isfinite(cpu->second) && cpu->second >= 100.0)
    return static_cast<unsigned>(cpu->second / 100.0);
  if (cores_property && *cores_property >= 1)
    return static_cast<unsigned>(*cores_property);
  return 1;
}

// The DCD's value for a device property (by id or name), as text.
std::optional<std::string> override_of(const profile::ComponentInstantiation &ci,
                                       const profile::SimpleProperty &property) {
  for (const auto &ref : ci.properties) {
    const auto *simple = std::get_if<profile::SimpleRef>(&ref);
    // An empty number is no override, as at the node (profile::is_empty_override).
    if (simple != nullptr && (simple->refid == property.id || simple->refid == property.name) &&
        !profile::is_empty_override(property, ref))
      return simple->value;
  }
  return std::nullopt;
}

std::vector<const profile::SimpleProperty *>
simple_properties(const profile::ResolvedSoftPkg &pkg) {
  std::vector<const profile::SimpleProperty *> out;
  if (pkg.properties == nullptr)
    return out;
  for (const auto &definition : pkg.properties->properties)
    if (const auto *simple = std::get_if<profile::SimpleProperty>(&definition))
      out.push_back(simple);
  return out;
}

std::map<std::string, std::string> deployer_requires_of(const profile::ComponentInstantiation &ci) {
  std::map<std::string, std::string> out;
  for (const auto &ref : ci.device_requires)
    if (const auto *simple = std::get_if<profile::SimpleRef>(&ref))
      out[simple->refid] = simple->value;
  return out;
}

} // namespace

Device describe_offline(const std::string &node, const std::string &id,
                        const profile::ComponentInstantiation &ci,
                        const profile::ResolvedSoftPkg &pkg) {
  Device device;
  device.id = id;
  device.node = node;
  device.kind = pkg.scd && pkg.scd->component_type == "executabledevice" ? "gpp" : "device";
  device.deployer_requires = deployer_requires_of(ci);
  std::optional<double> cores;
  for (const auto *p : simple_properties(pkg)) {
    std::optional<std::string> value = override_of(ci, *p);
    if (!value && p->value)
      value = profile::format_scalar(*p->value);
    if (p->label() == "nbCores" && value)
      cores = as_number(*value);
    if (p->label() == "scheduling_policy" && value)
      device.policy = parse_policy(*value).value_or(device.policy);
    if (!p->has_kind(profile::PropertyKind::Allocation))
      continue;
    const auto action = p->action.value_or(profile::Action::Eq);
    if (action == profile::Action::External) {
      device.capacity[p->label()] = value ? as_number(*value).value_or(kUnknown) : kUnknown;
      continue;
    }
    device.properties.push_back({p->id, p->label(), value.value_or(""), action});
  }
  device.cpus = cpus_of(device, cores);
  return device;
}

const MatchingProperty *Device::find_property(std::string_view id_or_name) const {
  for (const auto &p : properties)
    if (p.id == id_or_name || p.name == id_or_name)
      return &p;
  return nullptr;
}

std::string Device::property_value(std::string_view id_or_name) const {
  const auto *p = find_property(id_or_name);
  return p == nullptr ? std::string() : p->value;
}

bool satisfies(const MatchingProperty &property, const std::string &required) {
  const auto device_number = as_number(property.value);
  const auto required_number = as_number(required);
  const int order = device_number && required_number ? compare(*device_number, *required_number)
                                                     : compare(property.value, required);
  const bool numeric = device_number && required_number;
  switch (property.action) {
  case profile::Action::Eq:
    return order == 0;
  case profile::Action::Ne:
    return order != 0;
  case profile::Action::Gt:
    return numeric && order > 0;
  case profile::Action::Lt:
    return numeric && order < 0;
  case profile::Action::Ge:
    return numeric && order >= 0;
  case profile::Action::Le:
    return numeric && order <= 0;
  case profile::Action::External:
    break;
  }
  return false;
}

std::string describe_amount(const std::string &capacity, double amount) {
  if (!std::isfinite(amount))
    return "unknown";
  if (capacity == kMemCapacity)
    return fmt::format("{:.0f} MiB", amount);
  if (capacity == kCpuCapacity)
    return fmt::format("{:.1f}% CPU", amount);
  if (capacity == kNetCapacity)
    return fmt::format("{:g} Mbps", amount);
  return fmt::format("{:g}", amount);
}

json allocation_properties_json(const profile::ResolvedSoftPkg &device_pkg) {
  json out = json::array();
  for (const auto *p : simple_properties(device_pkg))
    if (p->has_kind(profile::PropertyKind::Allocation))
      out.push_back({{"id", p->id},
                     {"name", p->label()},
                     {"action", profile::to_string(p->action.value_or(profile::Action::Eq))}});
  return out;
}

Device device_from_announcement(const std::string &node, const json &entry) {
  Device device;
  device.id = entry.value("id", "");
  device.node = node;
  device.kind = entry.value("kind", "device");
  // Copies: items() of a temporary would outlive it.
  const json properties = entry.value("properties", json::object());
  const json capacity = entry.value("capacity", json::object());
  const json allocation = entry.value("allocation", json::array());
  const json deployer_requires = entry.value("deployerrequires", json::object());
  for (const auto &[k, v] : capacity.items())
    if (v.is_number())
      device.capacity[k] = v.get<double>();
  // Allocation properties as the device's PRF declares them, valued by what the device reports.
  for (const auto &a : allocation) {
    const std::string name = a.value("name", ""), id = a.value("id", name);
    const auto action = parse_action(a.value("action", "eq")).value_or(profile::Action::Eq);
    if (action == profile::Action::External)
      continue;
    const json *value = properties.contains(name) ? &properties.at(name)
                        : properties.contains(id) ? &properties.at(id)
                                                  : nullptr;
    device.properties.push_back({id, name, value ? text_of(*value) : "", action});
  }
  // Reported properties the PRF does not declare as allocation properties still match by eq.
  for (const auto &[k, v] : properties.items())
    if (device.find_property(k) == nullptr)
      device.properties.push_back({k, k, text_of(v), profile::Action::Eq});
  for (const auto &[k, v] : deployer_requires.items())
    device.deployer_requires[k] = text_of(v);
  device.policy = parse_policy(device.property_value("scheduling_policy")).value_or(device.policy);
  device.cpus = cpus_of(device, std::nullopt);
  return device;
}

std::vector<Device> devices_of_node(const profile::ResolvedNode &node) {
  std::vector<Device> out;
  for (const auto &placed : node.devices) {
    // A device whose package misses a file does not start at its node: not in the domain.
    if (!placed.softpkg || placed.placement == nullptr || !placed.softpkg->unavailable.empty())
      continue;
    for (const auto &ci : placed.placement->instantiations) {
      const std::string label = ci.usage_name.empty() ? ci.id : ci.usage_name;
      out.push_back(describe_offline(node.dcd->name, fmt::format("{}:{}", node.dcd->name, label),
                                     ci, *placed.softpkg));
    }
  }
  return out;
}

} // namespace rsca::allocator
