// DeviceManager: the node daemon. Reads its DCD, starts the logical devices it names (each from
// the library its SPD names, node/device_libraries.hpp), announces
// the node and its devices to the domain, and serves node.execute / node.terminate for its
// executable devices. It needs no registration protocol: its announcement is durable, so a
// domain daemon that (re)starts sees it at once.
#pragma once

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

#include "node/logical_device.hpp"
#include "node/package_cache.hpp"
#include "shm/ring.hpp"

namespace rsca::node {

struct NodeOptions {
  std::filesystem::path dcd;
  std::optional<std::filesystem::path> sdrroot;
  std::string domain_name = "rsca";
  std::vector<std::filesystem::path> exec_path;
  // Where a device library an SPD names without a path that is not beside it is looked for
  // (node/device_libraries.hpp). Empty: rsca's library folders (common/install_layout.hpp).
  std::vector<std::filesystem::path> library_path;
  std::filesystem::path log_dir = "/tmp/rsca/logs";
  // A process's log past this is rotated, one older file kept (node/process_logs.hpp); 0: never.
  std::uint64_t log_max_bytes = 10ULL << 20U;
  // The logs no running process writes (released applications', rolled-back launches') are
  // deleted once unwritten for this long (node/process_logs.hpp, sweep_logs).
  std::chrono::hours log_keep{24 * 7};
  // Where local clients (the CLI) connect for a link to the node (ProcessLinks::listen); none:
  // they use DDS.
  std::optional<std::filesystem::path> control_socket;
  // Each ring of same-host data (one per topic with ends on this host): its bytes of data (a
  // sample takes at most half) and records (the most a reader may fall behind).
  shm::RingLimits rings;
  // The cache of the packages its processes run inside (node/package_cache.hpp). Its folder
  // empty: <log_dir>/../cache/<node name>.
  CacheOptions cache;
};

class DeviceManager {
public:
  static Expected<std::unique_ptr<DeviceManager>>
  create(std::shared_ptr<dds::Participant> participant, NodeOptions options);
  ~DeviceManager();

  const std::string &node_name() const;

  struct Impl;

private:
  explicit DeviceManager(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

} // namespace rsca::node
