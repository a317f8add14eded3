// The device libraries of a node (node/device_export.hpp): a device whose SPD's code is a
// SharedLibrary is implemented by that library, which rsca-noded loads when it starts the device.
// Each library is loaded once, however many devices name it, and stays loaded for the life of
// the process (RTLD_NODELETE): its devices' threads may outlive them.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>

#include "node/logical_device.hpp"
#include "profile/profile_loader.hpp"

namespace rsca::node {

// Why a device has no factory: the file and the symbol involved, apart, for the node's
// announcement (protocol/node_ops.hpp, FailedDevice), and the whole reason, naming both.
struct LoadFailure {
  std::string file;   // the library tried; empty when the SPD names none
  std::string symbol; // the symbol looked up; empty when the library was not opened
  std::string reason;
};

class DeviceLibraries {
public:
  // The library as the SPD names it: absolute, or relative to the SPD's folder; one that is not
  // there is looked up by file name in `folders` (common/install_layout.hpp: rsca's library
  // folders, built or installed).
  explicit DeviceLibraries(std::vector<std::filesystem::path> folders)
      : folders_(std::move(folders)) {}

  // The factory of the device `softpkg` describes, from the library its SPD's first SharedLibrary
  // implementation names, loaded into `registry` the first time. Fails with why, naming the file
  // and the symbol: the SPD names no library, the library cannot be loaded, exports no
  // kDeviceFactoriesSymbol, or registers no device of the SPD's name.
  tl::expected<const DeviceFactory *, LoadFailure>
  factory_of(const profile::ResolvedSoftPkg &softpkg, DeviceRegistry &registry);

private:
  std::optional<LoadFailure> load(const std::filesystem::path &library, DeviceRegistry &registry);

  std::vector<std::filesystem::path> folders_;
  // Each library tried, by resolved path: nothing when loaded, else why it could not be.
  std::map<std::filesystem::path, std::optional<LoadFailure>> tried_;
};

} // namespace rsca::node
