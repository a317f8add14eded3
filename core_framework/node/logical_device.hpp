// The device plugin interface of the DeviceManager: a logical device says what it is (matching
// properties, capacities) and, if it is an ExecutableDevice such as the GPP, runs processes.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "control/endpoint.hpp"
#include "dds/dds_settings.hpp"
#include "dds/participant.hpp"
#include "node/package_cache.hpp"
#include "node/process_links.hpp"
#include "profile/profile_loader.hpp"
#include "protocol/domain_ops.hpp"
#include "protocol/node_ops.hpp"

namespace rsca::node {

using control::CallResult;
using control::Json;

// What a device is given when its node starts it.
struct DeviceContext {
  std::string id;    // "<node>:<usage name>"
  std::string label; // the DCD's usage name
  std::string node;
  std::string domain;
  std::shared_ptr<const profile::ResolvedSoftPkg> softpkg;
  const profile::ComponentInstantiation *instantiation = nullptr; // in the DCD
  Json overrides; // the DCD's property values for this device, by property name and id
  std::shared_ptr<dds::Participant> participant; // the node's: devices with ports join it
  std::vector<std::filesystem::path> exec_path;  // where bare entrypoint names are looked for
  std::filesystem::path log_dir;                 // component logs go here
  dds::DdsSettings dds;                          // what launched processes must join
  // Reports a process that exited on its own (a crash, for a component). Must not block.
  std::function<void(const protocol::domain::ComponentExitedReport &report)> report_exit;
  // The node's links to the processes it starts (node/process_links.hpp): a started process
  // gets one, and its control goes through the node. Null: processes join DDS on their own.
  ProcessLinks *links = nullptr;
  // The host's shared memory (node/host_data.hpp): a started process maps its arena. Null: its
  // connections to other processes of this host go over DDS.
  HostData *host_data = nullptr;
};

class LogicalDevice {
public:
  virtual ~LogicalDevice() = default;
  virtual std::string kind() const = 0; // "gpp" runs components; "device" is used by them
  virtual Json properties() const = 0;  // matching properties, by name
  virtual Json capacity() const = 0;    // total capacities, by name
  // Devices with data ports serve them at a control address, as components do.
  virtual std::string address() const { return {}; }
  virtual std::vector<protocol::node::DevicePort> ports() const { return {}; }
};

class ExecutableDevice : public LogicalDevice {
public:
  // Starts the process the request names. With a package (node/package_cache.hpp), inside it:
  // the process runs in the package's folder, the paths the request names relative to it, and
  // the lease is kept for as long as the process runs.
  virtual CallResult<protocol::node::ExecuteReply>
  execute(const protocol::node::ExecuteRequest &request,
          std::shared_ptr<const PackageLease> package) = 0;
  // Fails with NotFound for a process this device did not start.
  virtual CallResult<protocol::node::TerminateReply>
  terminate(const protocol::node::TerminateRequest &request) = 0;
  virtual std::vector<protocol::node::ProcessRecord> processes() const = 0;
};

using DeviceFactory =
    std::function<Expected<std::unique_ptr<LogicalDevice>>(const DeviceContext &context)>;

// Device implementations by the name of their SPD (softpkg name attribute).
class DeviceRegistry {
public:
  void add(std::string softpkg_name, DeviceFactory factory) {
    factories_[std::move(softpkg_name)] = std::move(factory);
  }
  const DeviceFactory *find(const std::string &softpkg_name) const {
    auto it = factories_.find(softpkg_name);
    return it == factories_.end() ? nullptr : &it->second;
  }

private:
  std::map<std::string, DeviceFactory> factories_;
};

} // namespace rsca::node
