#include "allocator/resource_allocator.hpp"

#include <algorithm>

namespace rsca::allocator {
namespace {

// Every device a plan reserves something on.
std::set<std::string> devices_of(const Plan &plan) {
  std::set<std::string> ids;
  for (const auto &p : plan.placements) {
    ids.insert(p.device);
    for (const auto &used : p.used_devices)
      ids.insert(used.device);
  }
  for (const auto &used : plan.application_devices)
    ids.insert(used.device);
  return ids;
}

// The part of `plan` reserved on the devices `held`: what may be given back.
Plan part_on(const Plan &plan, const std::set<std::string> &held) {
  auto held_by = [&](const std::string &device) { return held.count(device) != 0; };
  auto drop_gone = [&](std::vector<UsedDevice> &used) {
    std::erase_if(used, [&](const UsedDevice &u) { return !held_by(u.device); });
  };
  Plan part = plan;
  for (auto &p : part.placements) {
    if (!held_by(p.device)) {
      p.demand.clear();
      p.task.reset();
    }
    drop_gone(p.used_devices);
  }
  drop_gone(part.application_devices);
  return part;
}

} // namespace

void ResourceAllocator::set_node_devices(const std::string &node, std::vector<Device> devices) {
  std::lock_guard lock(mutex_);
  suspended_.erase(node);
  DomainState kept;
  for (auto &[id, state] : devices_)
    if (state.device.node != node)
      kept.emplace(id, std::move(state));
  std::set<std::string> remaining;
  for (auto &d : devices) {
    auto old = devices_.find(d.id);
    DeviceState state{std::move(d), {}};
    if (old != devices_.end() && old->second.device.node == node) {
      state.load = old->second.load;
      remaining.insert(old->first);
    }
    const std::string id = state.device.id;
    kept.emplace(id, std::move(state));
  }
  std::set<std::string> gone;
  for (const auto &[id, state] : devices_)
    if (state.device.node == node && remaining.count(id) == 0)
      gone.insert(id);
  devices_ = std::move(kept);
  forget_devices_locked(gone);
}

void ResourceAllocator::suspend_node(const std::string &node) {
  std::lock_guard lock(mutex_);
  suspended_.insert(node);
}

DomainState ResourceAllocator::plannable_locked() const {
  if (suspended_.empty())
    return devices_;
  DomainState plannable;
  for (const auto &[id, state] : devices_)
    if (suspended_.count(state.device.node) == 0)
      plannable.emplace(id, state);
  return plannable;
}

void ResourceAllocator::remove_node(const std::string &node) {
  std::lock_guard lock(mutex_);
  suspended_.erase(node);
  std::set<std::string> gone;
  for (const auto &[id, state] : devices_)
    if (state.device.node == node)
      gone.insert(id);
  std::erase_if(devices_, [&](const auto &entry) { return gone.count(entry.first) != 0; });
  forget_devices_locked(gone);
}

void ResourceAllocator::forget_devices_locked(const std::set<std::string> &gone) {
  if (gone.empty())
    return;
  for (auto &[id, reservation] : reservations_)
    std::erase_if(reservation.held, [&](const std::string &d) { return gone.count(d) != 0; });
}

tl::expected<Plan, std::vector<Rejection>>
ResourceAllocator::plan(const PlanRequest &request, const PlanOptions &options) const {
  std::lock_guard lock(mutex_);
  return make_plan(plannable_locked(), request, options);
}

tl::expected<Plan, std::vector<Rejection>> ResourceAllocator::allocate(const PlanRequest &request,
                                                                       const PlanOptions &options) {
  std::lock_guard lock(mutex_);
  auto plan = make_plan(plannable_locked(), request, options);
  if (!plan)
    return plan;
  commit(devices_, *plan); // on devices plannable_locked() copied: the same ids
  plan->allocation = ++last_allocation_;
  reservations_.emplace(plan->allocation, Reservation{*plan, devices_of(*plan)});
  return plan;
}

void ResourceAllocator::release(const Plan &plan) {
  std::lock_guard lock(mutex_);
  auto it = reservations_.find(plan.allocation);
  if (it == reservations_.end())
    return; // it reserved nothing, or was given back already
  allocator::release(devices_, part_on(it->second.plan, it->second.held));
  reservations_.erase(it);
}

DomainState ResourceAllocator::snapshot() const {
  std::lock_guard lock(mutex_);
  return devices_;
}

std::size_t ResourceAllocator::reservations() const {
  std::lock_guard lock(mutex_);
  return reservations_.size();
}

} // namespace rsca::allocator
