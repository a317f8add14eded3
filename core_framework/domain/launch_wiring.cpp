// The connect step of a launch: each SAD connection's ends resolved (a component's port, a
// device's, an event channel), then made by the wiring service (domain/wiring.hpp).
#include <algorithm>
#include <filesystem>
#include <map>
#include <set>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/elapsed.hpp"
#include "dds/port_qos.hpp"
#include "domain/launch.hpp"
#include "domain/wiring.hpp"
#include "profile/connection_qos.hpp"
#include "profile/property_binding.hpp"
#include "profile/property_json.hpp"
#include "protocol/component_ops.hpp"
#include "protocol/topics.hpp"

namespace rsca::domain {

using namespace detail;

CallResult<void> ApplicationFactory::Launch::connect() {
  const auto &sad = *request_.profile->sad;
  for (std::size_t i = 0; i < sad.connections.size(); ++i) {
    auto ci = connection_of(sad.connections[i], i);
    if (!ci)
      return tl::unexpected(ci.error());
    app_->connections.push_back(std::move(*ci));
  }
  // Devices outlive the application: their ends of its connections are undone on their own (the
  // components' ends go with their processes).
  saga_.on_undo([this] {
    const auto ends = ApplicationFactory(s_).disconnect_devices(*app_);
    return ends == 0 ? std::string()
                     : fmt::format("{} device end{} disconnected", ends, ends == 1 ? "" : "s");
  });
  std::vector<Wire> wires;
  wires.reserve(app_->connections.size());
  for (const auto &ci : app_->connections)
    wires.push_back(wire_of(ci));
  std::vector<WireEnd> made;
  auto times = Wiring(*s_.endpoint, s_.call_timeout).connect(wires, made);
  if (!times)
    return tl::unexpected(times.error());
  detail_ = fmt::format("{} connections (readers {:.0f} ms, writers {:.0f} ms, matched {:.0f} ms)",
                        app_->connections.size(), times->readers_ms, times->writers_ms,
                        times->matched_ms);
  return {};
}

CallResult<ConnectionInstance>
ApplicationFactory::Launch::connection_of(const profile::Connection &c, std::size_t index) {
  ConnectionInstance ci;
  ci.id = connection_id(c, index);
  ci.qos = dds::qos_to_json(c.qos.value_or(profile::ConnectionQos{}));
  const bool member = c.publishes_to_channel() || c.subscribes_to_channel();
  ci.channel = member ? channel_name(c) : "";
  ci.topic = member ? s_.channels->topic_of(ci.channel)
                    : protocol::connection_topic(s_.domain_name, app_->name, launch_, ci.id);
  ci.filter = c.filter.value_or("");
  ci.repid = repid_of(c);
  auto uses = resolve_end(ci, c.uses.target, c.uses.port, profile::PortDirection::Uses);
  if (!uses)
    return tl::unexpected(uses.error());
  ci.uses = std::move(*uses);
  if (c.provides.kind == profile::ProvidesEnd::Kind::SupportedInterface) {
    // The component itself, at its control address: no topic, nothing to make on its side.
    ci.topic.clear();
    ci.provides = {c.provides.target.refid, "", "", component_of(c.provides.target.refid)->address};
    return ci;
  }
  if (c.provides.kind == profile::ProvidesEnd::Kind::Port) {
    auto provides =
        resolve_end(ci, c.provides.target, c.provides.port, profile::PortDirection::Provides);
    if (!provides)
      return tl::unexpected(provides.error());
    ci.provides = std::move(*provides);
  }
  return ci;
}

// A SAD connection as the wiring service makes it. An event channel's member waits for this
// application's members on the other side of the channel.
Wire ApplicationFactory::Launch::wire_of(const ConnectionInstance &ci) const {
  Wire w;
  w.topic = ci.topic;
  w.repid = ci.repid;
  w.qos = ci.qos;
  w.filter = ci.filter;
  auto end_of = [&](const ConnectionEnd &end, int peers, std::string what) {
    const auto *component = end.component.empty() ? nullptr : component_of(end.component);
    return WireEnd{end.address,
                   end.port,
                   end_key(ci, end),
                   component ? component->host : "",
                   peers,
                   std::move(what),
                   component ? component->relaying_node() : ""};
  };
  if (ci.is_interface()) {
    w.interface_target = ci.provides.address;
    if (const auto *target = component_of(ci.provides.component))
      w.interface_via = target->via;
    w.uses =
        end_of(ci.uses, 0, fmt::format("{} ({} -> {})", ci.id, ci.uses.name(), ci.provides.name()));
    return w;
  }
  const bool channel = ci.uses.empty() || ci.provides.empty();
  if (!ci.uses.empty())
    w.uses = end_of(ci.uses, channel ? channel_peers(ci, ci.uses, /*subscribers=*/true) : 1,
                    fmt::format("{} ({})", ci.id, ci.uses.name()));
  if (!ci.provides.empty())
    w.provides =
        end_of(ci.provides, channel ? channel_peers(ci, ci.provides, /*subscribers=*/false) : 1,
               fmt::format("{} ({})", ci.id, ci.provides.name()));
  return w;
}

CallResult<ConnectionEnd>
ApplicationFactory::Launch::resolve_end(ConnectionInstance &ci,
                                        const profile::EndpointTarget &target,
                                        const std::string &port, profile::PortDirection direction) {
  using Kind = profile::EndpointTarget::Kind;
  if (target.kind == Kind::FindBy)
    return ConnectionEnd{};
  if (target.kind == Kind::ComponentInstantiation)
    return ConnectionEnd{target.refid, port, "", component_of(target.refid)->address};
  auto device = device_of(target);
  if (!device)
    return control::call_error(Status::BadRequest,
                               fmt::format("connection {}: {}", ci.id, device.error()));
  return device_end(ci, *device, port, direction);
}

tl::expected<std::string, std::string>
ApplicationFactory::Launch::device_of(const profile::EndpointTarget &target) const {
  // The SAD's own usesdevice (deviceusedbyapplication): the device the plan gave the application.
  if (target.kind == profile::EndpointTarget::Kind::DeviceUsedByApplication) {
    for (const auto &used : app_->plan.application_devices)
      if (used.uses_id == target.usesrefid)
        return used.device;
    return tl::unexpected(fmt::format("the application has no usesdevice {}", target.usesrefid));
  }
  const auto *placement = placement_of(target.refid);
  if (placement == nullptr)
    return tl::unexpected(fmt::format("no component {} in the application", target.refid));
  if (target.kind == profile::EndpointTarget::Kind::DeviceThatLoadedThisComponent)
    return placement->device;
  for (const auto &used : placement->used_devices)
    if (used.uses_id == target.usesrefid)
      return used.device;
  return tl::unexpected(
      fmt::format("component {} has no usesdevice {}", target.refid, target.usesrefid));
}

CallResult<ConnectionEnd> ApplicationFactory::Launch::device_end(ConnectionInstance &ci,
                                                                 const std::string &device,
                                                                 const std::string &port,
                                                                 profile::PortDirection direction) {
  const auto wanted = profile::to_string(direction);
  auto ports = s_.device_ports ? s_.device_ports(device) : std::nullopt;
  const protocol::node::DevicePort *found = nullptr;
  if (ports)
    for (const auto &p : ports->ports)
      if (p.name == port && p.direction == wanted)
        found = &p;
  if (found == nullptr)
    return control::call_error(
        Status::BadRequest,
        fmt::format("connection {}: device {} has no {} port {}", ci.id, device, wanted, port));
  const std::string repid = found->repid;
  if (ci.repid.empty())
    ci.repid = repid;
  if (repid != ci.repid)
    return control::call_error(Status::BadRequest,
                               fmt::format("connection {}: port type: device port {}.{} carries "
                                           "{}, but the other end carries {}",
                                           ci.id, device, port, repid, ci.repid));
  return ConnectionEnd{"", port, device, ports->address};
}

// Where an end's data goes: through the ring of the node that relays for its process (`node`
// not empty), or from its owner itself (a device; a QoS asking for direct DDS or a TCP stream).
std::string ApplicationFactory::Launch::relaying_node_of(const ConnectionInstance &ci,
                                                         const ConnectionEnd &end) const {
  const auto *component = end.component.empty() ? nullptr : component_of(end.component);
  if (component == nullptr)
    return {};
  const auto qos = dds::connection_qos_from_json(ci.qos);
  if (qos && qos->transport != profile::Transport::Node)
    return {}; // DDS from its own process, or a TCP stream
  return component->relaying_node();
}

// The peers an event channel's member of this application waits for, counted as its end sees
// them: each member on the other side in the same node's ring; for each other node, that node's
// relay; each member on DDS of its own (wiring.hpp: the end's matched count).
int ApplicationFactory::Launch::channel_peers(const ConnectionInstance &self,
                                              const ConnectionEnd &end, bool subscribers) const {
  const std::string here = relaying_node_of(self, end);
  int peers = 0;
  std::set<std::string> relays;
  for (const auto &ci : app_->connections) {
    const auto &other = subscribers ? ci.provides : ci.uses;
    if (ci.topic != self.topic || other.empty())
      continue;
    const std::string there = relaying_node_of(ci, other);
    if (there.empty() || (!here.empty() && there == here))
      ++peers;
    else
      relays.insert(there);
  }
  return peers + static_cast<int>(relays.size());
}

std::string ApplicationFactory::Launch::repid_of(const profile::Connection &c) const {
  for (const auto *end : {&c.uses.target, &c.provides.target}) {
    if (end->kind != profile::EndpointTarget::Kind::ComponentInstantiation)
      continue;
    const profile::ComponentPlacement *placement = nullptr;
    if (instantiation_of(end->refid, &placement) == nullptr)
      continue;
    const auto *pkg = request_.profile->softpkg_of(*placement);
    if (pkg == nullptr || !pkg->scd)
      continue;
    const bool uses = end == &c.uses.target;
    if (!uses && c.provides.kind != profile::ProvidesEnd::Kind::Port)
      continue; // a supported interface's repid, not a port
    const auto *port =
        pkg->scd->find_port(uses ? c.uses.port : c.provides.port,
                            uses ? profile::PortDirection::Uses : profile::PortDirection::Provides);
    if (port != nullptr)
      return port->repid;
  }
  return {};
}

} // namespace rsca::domain

namespace rsca::domain {

// A connection of `c` that asks for direct DDS goes on DDS from c's own process (every other
// one goes through its node: docs/architecture.md, "Data through the nodes"): the process then
// joins DDS as it starts, so that DDS discovery overlaps the launch's steps before `connect`
// instead of adding to it.
bool ApplicationFactory::Launch::joins_dds(const ComponentInstance &c) const {
  using Kind = profile::EndpointTarget::Kind;
  if (c.relaying_node().empty())
    return false; // a process no node relays for joins DDS when it connects, as it always did
  for (const auto &conn : request_.profile->sad->connections) {
    if (conn.provides.kind == profile::ProvidesEnd::Kind::SupportedInterface)
      continue; // control calls: through the node
    const bool provides_port = conn.provides.kind == profile::ProvidesEnd::Kind::Port;
    const auto is_end = [&c](const profile::EndpointTarget &t) {
      return t.kind == Kind::ComponentInstantiation && t.refid == c.id;
    };
    if (!is_end(conn.uses.target) && !(provides_port && is_end(conn.provides.target)))
      continue;
    // Named, or taken by the domain for a QoS the nodes cannot honour (dds/port_qos.cpp).
    if (conn.qos && conn.qos->transport.value_or(profile::transport_for(*conn.qos)) ==
                        profile::Transport::Direct)
      return true;
  }
  return false;
}

} // namespace rsca::domain
