// A device library for the tests of node/device_libraries.hpp: it registers one device, whose
// factory makes nothing, and calls no rsca code (the unit tests export none).
#include "node/device_export.hpp"

namespace {

int entries = 0; // how often a node entered the library

void register_test_devices(rsca::node::DeviceRegistry &registry) {
  ++entries;
  registry.add("TestDevice", [](const rsca::node::DeviceContext &) {
    return rsca::Expected<std::unique_ptr<rsca::node::LogicalDevice>>(nullptr);
  });
}

} // namespace

RSCA_DEVICES(register_test_devices)

extern "C" int rsca_test_device_entries() {
  return entries;
}
