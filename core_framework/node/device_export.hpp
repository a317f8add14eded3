// How a device library names its devices to the node that loads it:
//
//   void register_my_devices(rsca::node::DeviceRegistry &registry) {
//     registry.add("MyDevice", rsca::node::hosted_device<MyDevice>()); // by its SPD's name
//   }
//   RSCA_DEVICES(register_my_devices)
//
// defines the one symbol (kDeviceFactoriesSymbol) rsca-noded looks up in a library a device's
// SPD names (code type SharedLibrary). The library links no rsca library: rsca-noded exports the
// node and component runtime it was built with, so a device shares the node's participant, logger
// and shared memory.
#pragma once

#include "node/logical_device.hpp"

namespace rsca::node {

inline constexpr const char *kDeviceFactoriesSymbol = "rsca_device_factories";
using DeviceFactoriesExport = void (*)(DeviceRegistry *registry);

} // namespace rsca::node

#define RSCA_DEVICES(register_function)                                                            \
  extern "C" void rsca_device_factories(::rsca::node::DeviceRegistry *registry) {                  \
    register_function(*registry);                                                                  \
  }
