// ResourceAllocator: the domain's devices and what is reserved on them. Admission and placement
// are planned on a snapshot (allocator/planner.hpp) and committed whole: an application is
// placed entirely or not at all, never over-committed, and everything is given back on release.
//
// Every allocate is a reservation of its own (Plan::allocation names it), recorded with the
// devices that still hold its share. A device that leaves (its node gone, or no longer
// announced) drops its load and its part of every reservation, so that a release gives back only
// what the application still holds: never a share that a node which went away and came back
// never gave it (issue 18, defect 4: it freed the share of the application placed there since).
#pragma once

#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "allocator/planner.hpp"

namespace rsca::allocator {

class ResourceAllocator {
public:
  // Replaces the devices of `node` (a node that (re)announces itself); what is reserved on
  // devices that remain is kept, what was reserved on the others is forgotten.
  void set_node_devices(const std::string &node, std::vector<Device> devices);
  // Forgets a node and everything reserved on its devices.
  void remove_node(const std::string &node);
  // A node that is lost (unreachable; its processes may still run): its devices keep what is
  // reserved on them but take no new placement until set_node_devices says it is back.
  void suspend_node(const std::string &node);

  // Plans on the current state and reserves nothing (rsca plan).
  tl::expected<Plan, std::vector<Rejection>> plan(const PlanRequest &request,
                                                  const PlanOptions &options) const;
  // Plans and reserves, all or nothing: a rejection changes nothing. The plan's `allocation`
  // names the reservation.
  tl::expected<Plan, std::vector<Rejection>> allocate(const PlanRequest &request,
                                                      const PlanOptions &options);
  // Gives back what the reservation `plan.allocation` still holds, as it was reserved, on the
  // devices that still hold it. A plan that reserved nothing, or was released already, gives
  // back nothing.
  void release(const Plan &plan);

  DomainState snapshot() const;
  // Reservations not released yet (also those whose devices are all gone).
  std::size_t reservations() const;

private:
  struct Reservation {
    Plan plan;                  // as committed
    std::set<std::string> held; // devices that still hold their part of it
  };

  // Drops the devices `gone` from every reservation. Called with mutex_ held.
  void forget_devices_locked(const std::set<std::string> &gone);

  // The devices plans may use: all but those of suspended nodes. Called with mutex_ held.
  DomainState plannable_locked() const;

  mutable std::mutex mutex_;
  DomainState devices_;
  std::set<std::string> suspended_; // nodes
  std::map<AllocationId, Reservation> reservations_;
  AllocationId last_allocation_ = 0;
};

} // namespace rsca::allocator
