#include "allocator/resource_allocator.hpp"

#include <algorithm>

namespace rsca::allocator {

void ResourceAllocator::set_node_devices(const std::string &node, std::vector<Device> devices) {
  std::lock_guard lock(mutex_);
  DomainState kept;
  for (auto &[id, state] : devices_)
    if (state.device.node != node)
      kept.emplace(id, std::move(state));
  for (auto &d : devices) {
    auto old = devices_.find(d.id);
    DeviceState state{std::move(d), {}};
    if (old != devices_.end() && old->second.device.node == node)
      state.load = old->second.load;
    const std::string id = state.device.id;
    kept.emplace(id, std::move(state));
  }
  devices_ = std::move(kept);
}

void ResourceAllocator::remove_node(const std::string &node) {
  std::lock_guard lock(mutex_);
  std::erase_if(devices_, [&](const auto &entry) { return entry.second.device.node == node; });
}

tl::expected<Plan, std::vector<Rejection>>
ResourceAllocator::plan(const PlanRequest &request, const PlanOptions &options) const {
  std::lock_guard lock(mutex_);
  return make_plan(devices_, request, options);
}

tl::expected<Plan, std::vector<Rejection>> ResourceAllocator::allocate(const PlanRequest &request,
                                                                       const PlanOptions &options) {
  std::lock_guard lock(mutex_);
  auto plan = make_plan(devices_, request, options);
  if (plan)
    commit(devices_, *plan);
  return plan;
}

void ResourceAllocator::release(const Plan &plan) {
  std::lock_guard lock(mutex_);
  allocator::release(devices_, plan);
}

DomainState ResourceAllocator::snapshot() const {
  std::lock_guard lock(mutex_);
  return devices_;
}

} // namespace rsca::allocator
