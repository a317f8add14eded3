// ResourceAllocator: which device runs each component, and the capacity that reserves there.
// Allocation is transactional — a request is placed entirely or not at all — and a rejection
// says, per component, why each device considered could not take it.
#pragma once

#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/diagnostic.hpp"
#include "profile/profile_loader.hpp"

namespace rsca::allocator {

// Capacity names, as the GPP's PRF declares them.
inline constexpr const char *kCpuCapacity = "cpu_capacity"; // percent of one core
inline constexpr const char *kMemCapacity = "mem_capacity"; // MiB

// A device as the allocator sees it.
struct Device {
  std::string id;   // e.g. "node1:GPP_1"
  std::string node; // its node's name
  std::string kind; // "gpp" runs components; others are used through usesdevice
  std::map<std::string, std::string> properties; // matching properties by name (os_name, ...)
  std::map<std::string, double> capacity;        // total, by capacity name
};

// One component instance to place.
struct Request {
  std::string instance;
  const profile::ResolvedSoftPkg *softpkg = nullptr;
  std::optional<std::string> device; // an explicit assignment (rsca launch --assign)
};

struct Placement {
  std::string instance;
  std::string device;
  std::string node;
  const profile::Implementation *implementation = nullptr;
  std::map<std::string, double> demand; // what was reserved on the device
};

// Why a request could not be placed: per component, each device and what failed there.
struct Rejection {
  std::string instance;
  std::vector<std::string> reasons; // "node2:GPP_1: mem_capacity needs 512 MiB, 200 MiB free"
};
std::string to_string(const std::vector<Rejection> &rejections);

// The capacity an implementation demands, from its RSCA resource demand (none declared: zero).
std::map<std::string, double> demand_of(const profile::Implementation &implementation);

class ResourceAllocator {
public:
  // Replaces the devices of `node` (a node that (re)announces itself); allocations on devices
  // that remain are kept.
  void set_node_devices(const std::string &node, std::vector<Device> devices);
  // Forgets a node and every allocation on its devices.
  void remove_node(const std::string &node);

  // Places every request or none; on success the capacity is reserved.
  tl::expected<std::vector<Placement>, std::vector<Rejection>>
  allocate(const std::vector<Request> &requests);
  void release(const std::vector<Placement> &placements);

  struct DeviceState {
    Device device;
    std::map<std::string, double> allocated;
  };
  std::vector<DeviceState> snapshot() const;

private:
  mutable std::mutex mutex_;
  std::map<std::string, DeviceState> devices_; // by device id: deterministic order
};

} // namespace rsca::allocator
