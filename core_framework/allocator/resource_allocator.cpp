#include "allocator/resource_allocator.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace rsca::allocator {
namespace {

using profile::Implementation;
using profile::ResolvedSoftPkg;

constexpr double kMiB = 1024.0 * 1024.0;

std::string property_or(const Device &device, const std::string &name) {
  auto it = device.properties.find(name);
  return it == device.properties.end() ? std::string() : it->second;
}

// The first reason `implementation` cannot run on `device`, or nothing when it can.
std::optional<std::string> mismatch(const Implementation &impl, const Device &device) {
  const std::string os = property_or(device, "os_name");
  if (!impl.os.empty() &&
      std::none_of(impl.os.begin(), impl.os.end(), [&](const auto &o) { return o.name == os; })) {
    std::vector<std::string> wanted;
    for (const auto &o : impl.os)
      wanted.push_back(o.name);
    return fmt::format("os_name is {}, implementation {} needs {}", os.empty() ? "unknown" : os,
                       impl.id, fmt::join(wanted, " or "));
  }
  const std::string processor = property_or(device, "processor_name");
  if (!impl.processors.empty() &&
      std::find(impl.processors.begin(), impl.processors.end(), processor) == impl.processors.end())
    return fmt::format("processor_name is {}, implementation {} needs {}",
                       processor.empty() ? "unknown" : processor, impl.id,
                       fmt::join(impl.processors, " or "));
  return std::nullopt;
}

// Whether every softpkg dependency of `impl` has an implementation that fits the same device
// (recursively, as SCA requires: dependencies load where the component loads).
std::optional<std::string> dependency_mismatch(const profile::ResolvedImplementation &impl,
                                               const Device &device, int depth = 0) {
  if (depth > 32)
    return "softpkg dependencies nest too deep";
  for (const auto &dep : impl.dependencies) {
    bool fits = false;
    std::string why;
    for (const auto &candidate : dep.softpkg->implementations) {
      if (dep.implref && candidate.implementation->id != *dep.implref)
        continue;
      auto m = mismatch(*candidate.implementation, device);
      if (!m)
        m = dependency_mismatch(candidate, device, depth + 1);
      if (!m) {
        fits = true;
        break;
      }
      why = *m;
    }
    if (!fits)
      return fmt::format("dependency {}: {}", dep.softpkg->spd->name, why);
  }
  return std::nullopt;
}

std::string describe_amount(const std::string &capacity, double amount) {
  if (capacity == kMemCapacity)
    return fmt::format("{:.0f} MiB", amount);
  if (capacity == kCpuCapacity)
    return fmt::format("{:.1f}% CPU", amount);
  return fmt::format("{:g}", amount);
}

std::optional<std::string> capacity_shortfall(const std::map<std::string, double> &demand,
                                              const ResourceAllocator::DeviceState &state) {
  for (const auto &[name, amount] : demand) {
    if (amount <= 0)
      continue;
    auto total = state.device.capacity.find(name);
    if (total == state.device.capacity.end())
      return fmt::format("{}: the device has no {} capacity", name, name);
    auto used = state.allocated.find(name);
    const double free = total->second - (used == state.allocated.end() ? 0.0 : used->second);
    if (amount > free + 1e-9)
      return fmt::format("{} needs {}, {} free", name, describe_amount(name, amount),
                         describe_amount(name, std::max(0.0, free)));
  }
  return std::nullopt;
}

} // namespace

std::string to_string(const std::vector<Rejection> &rejections) {
  std::string out;
  for (const auto &r : rejections) {
    out += fmt::format("{}{}: no device can run it", out.empty() ? "" : "\n", r.instance);
    for (const auto &reason : r.reasons)
      out += fmt::format("\n  {}", reason);
  }
  return out;
}

std::map<std::string, double> demand_of(const Implementation &implementation) {
  std::map<std::string, double> demand;
  if (!implementation.resource_demand)
    return demand;
  const auto &d = *implementation.resource_demand;
  if (d.utilization)
    demand[kCpuCapacity] = *d.utilization * 100.0;
  if (d.execution_time && d.period && !d.execution_time->infinite() && !d.period->infinite() &&
      d.period->value->count() > 0)
    demand[kCpuCapacity] = 100.0 * static_cast<double>(d.execution_time->value->count()) /
                           static_cast<double>(d.period->value->count());
  if (d.memory_bytes)
    demand[kMemCapacity] = static_cast<double>(*d.memory_bytes) / kMiB;
  return demand;
}

void ResourceAllocator::set_node_devices(const std::string &node, std::vector<Device> devices) {
  std::lock_guard lock(mutex_);
  std::map<std::string, DeviceState> kept;
  for (auto &[id, state] : devices_)
    if (state.device.node != node)
      kept.emplace(id, std::move(state));
  for (auto &d : devices) {
    auto old = devices_.find(d.id);
    DeviceState state{std::move(d), {}};
    if (old != devices_.end() && old->second.device.node == node)
      state.allocated = old->second.allocated;
    const std::string id = state.device.id;
    kept.emplace(id, std::move(state));
  }
  devices_ = std::move(kept);
}

void ResourceAllocator::remove_node(const std::string &node) {
  std::lock_guard lock(mutex_);
  std::erase_if(devices_, [&](const auto &entry) { return entry.second.device.node == node; });
}

tl::expected<std::vector<Placement>, std::vector<Rejection>>
ResourceAllocator::allocate(const std::vector<Request> &requests) {
  std::lock_guard lock(mutex_);
  // Plan on a copy so that a rejected request changes nothing.
  auto plan = devices_;
  std::vector<Placement> placements;
  std::vector<Rejection> rejections;
  for (const auto &request : requests) {
    Rejection rejection{request.instance, {}};
    std::optional<Placement> chosen;
    for (const auto &impl : request.softpkg->implementations) {
      const auto demand = demand_of(*impl.implementation);
      for (auto &[id, state] : plan) {
        if (state.device.kind != "gpp" || (request.device && *request.device != id))
          continue;
        auto why = mismatch(*impl.implementation, state.device);
        if (!why)
          why = dependency_mismatch(impl, state.device);
        if (!why)
          why = capacity_shortfall(demand, state);
        if (why) {
          rejection.reasons.push_back(
              fmt::format("{} ({}): {}", id, impl.implementation->id, *why));
          continue;
        }
        for (const auto &[name, amount] : demand)
          state.allocated[name] += amount;
        chosen = Placement{request.instance, id, state.device.node, impl.implementation, demand};
        break;
      }
      if (chosen)
        break;
    }
    if (chosen) {
      placements.push_back(std::move(*chosen));
      continue;
    }
    if (rejection.reasons.empty())
      rejection.reasons.push_back(
          request.device
              ? fmt::format("the assigned device {} is not in the domain", *request.device)
              : "no device that runs components is in the domain");
    rejections.push_back(std::move(rejection));
  }
  if (!rejections.empty())
    return tl::unexpected(std::move(rejections));
  devices_ = std::move(plan);
  return placements;
}

void ResourceAllocator::release(const std::vector<Placement> &placements) {
  std::lock_guard lock(mutex_);
  for (const auto &p : placements) {
    auto it = devices_.find(p.device);
    if (it == devices_.end())
      continue; // its node is gone, and with it the allocation
    for (const auto &[name, amount] : p.demand) {
      double &used = it->second.allocated[name];
      used = std::max(0.0, used - amount);
    }
  }
}

std::vector<ResourceAllocator::DeviceState> ResourceAllocator::snapshot() const {
  std::lock_guard lock(mutex_);
  std::vector<DeviceState> out;
  for (const auto &[id, state] : devices_)
    out.push_back(state);
  return out;
}

} // namespace rsca::allocator
