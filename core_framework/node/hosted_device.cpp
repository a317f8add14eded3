#include "node/hosted_device.hpp"

#include <fmt/format.h>

#include "allocator/device.hpp"
#include "protocol/addresses.hpp"

namespace rsca::node {
namespace {

// The DCD's values of the device's properties, by id (the overrides carry names too).
Json values_by_id(const DeviceContext &context) {
  Json out = Json::object();
  for (const auto &[key, value] : context.overrides.items()) {
    const auto *definition = context.softpkg->find_property(key);
    if (definition != nullptr && profile::common_of(*definition).id == key)
      out[key] = value;
  }
  return out;
}

} // namespace

Expected<std::unique_ptr<LogicalDevice>> HostedDevice::create(const DeviceContext &context,
                                                              const component::Factory &factory) {
  const component::Context component_context{
      context.id,
      context.label,
      "",
      context.domain,
      context.softpkg->spd_path,
      protocol::device_address(context.domain, context.node, context.label),
      component::in_process_logger(context.id),
      std::nullopt};
  auto component = component::InProcessComponent::open(
      factory, component_context, context.softpkg,
      std::make_shared<component::ParticipantSource>(context.participant));
  if (!component)
    return tl::unexpected(component.error());
  if (auto up = (*component)->bring_up(values_by_id(context)); !up)
    return tl::unexpected(up.error());
  // What the allocator matches: the PRF's allocation properties with the DCD's values.
  const auto described = allocator::describe_offline(context.node, context.id,
                                                     *context.instantiation, *context.softpkg);
  Json properties = Json::object();
  for (const auto &p : described.properties)
    properties[p.name] = p.value;
  Json capacity = Json::object();
  for (const auto &[name, amount] : described.capacity)
    capacity[name] = amount;
  return std::unique_ptr<LogicalDevice>(
      new HostedDevice(std::move(*component), std::move(properties), std::move(capacity)));
}

} // namespace rsca::node
