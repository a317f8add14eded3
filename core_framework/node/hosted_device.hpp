// A device written as a component (component/component.hpp): properties bound to its PRF, data
// ports declared in its SCD. Its node runs it in-process, serves it at
// "<domain>/device/<node>/<label>" like a component, and brings it up at once with the DCD's
// property values; the domain connects its ports as it connects a component's.
#pragma once

#include <memory>

#include "component/in_process.hpp"
#include "node/logical_device.hpp"

namespace rsca::node {

class HostedDevice final : public LogicalDevice {
public:
  static Expected<std::unique_ptr<LogicalDevice>> create(const DeviceContext &context,
                                                         const component::Factory &factory);

  std::string kind() const override { return "device"; }
  Json properties() const override { return properties_; }
  Json capacity() const override { return capacity_; }
  std::string address() const override { return component_->address(); }
  std::vector<protocol::node::DevicePort> ports() const override { return component_->ports(); }

private:
  HostedDevice(std::unique_ptr<component::InProcessComponent> component, Json properties,
               Json capacity)
      : component_(std::move(component)), properties_(std::move(properties)),
        capacity_(std::move(capacity)) {}

  std::unique_ptr<component::InProcessComponent> component_;
  Json properties_;
  Json capacity_;
};

// The DeviceFactory of a device class T (a component::Component).
template <typename T>
DeviceFactory hosted_device() {
  return [](const DeviceContext &context) {
    return HostedDevice::create(context,
                                [](const component::Context &c) { return std::make_unique<T>(c); });
  };
}

} // namespace rsca::node
