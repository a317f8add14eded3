// ResourceAllocator: the domain's devices and what is reserved on them. Admission and placement
// are planned on a snapshot (allocator/planner.hpp) and committed whole: an application is
// placed entirely or not at all, never over-committed, and everything is given back on release.
#pragma once

#include <mutex>
#include <string>
#include <vector>

#include "allocator/planner.hpp"

namespace rsca::allocator {

class ResourceAllocator {
public:
  // Replaces the devices of `node` (a node that (re)announces itself); what is reserved on
  // devices that remain is kept.
  void set_node_devices(const std::string &node, std::vector<Device> devices);
  // Forgets a node and everything reserved on its devices.
  void remove_node(const std::string &node);

  // Plans on the current state and reserves nothing (rsca plan).
  tl::expected<Plan, std::vector<Rejection>> plan(const PlanRequest &request,
                                                  const PlanOptions &options) const;
  // Plans and reserves, all or nothing: a rejection changes nothing.
  tl::expected<Plan, std::vector<Rejection>> allocate(const PlanRequest &request,
                                                      const PlanOptions &options);
  void release(const Plan &plan);

  DomainState snapshot() const;

private:
  mutable std::mutex mutex_;
  DomainState devices_;
};

} // namespace rsca::allocator
