// The connect step of a launch: each SAD connection's ends resolved (a component's port, a
// device's, an event channel), the readers connected first, then the writers, then a wait until
// every connection has matched its peers.
#include <algorithm>
#include <filesystem>
#include <map>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "common/elapsed.hpp"
#include "dds/port_qos.hpp"
#include "domain/launch.hpp"
#include "profile/property_binding.hpp"
#include "profile/property_json.hpp"
#include "protocol/component_ops.hpp"
#include "protocol/topics.hpp"

namespace rsca::domain {

using namespace detail;

CallResult<void> ApplicationFactory::Launch::connect() {
  const auto &sad = *request_.profile->sad;
  std::vector<Call> provides_side, uses_side;
  for (std::size_t i = 0; i < sad.connections.size(); ++i) {
    const auto &c = sad.connections[i];
    ConnectionInstance ci;
    ci.id = connection_id(c, i);
    ci.qos = dds::qos_to_json(c.qos.value_or(profile::ConnectionQos{}));
    ci.topic = c.publishes_to_channel() || c.subscribes_to_channel()
                   ? s_.channels->topic_of(channel_name(c))
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
      ci.provides = {c.provides.target.refid, "", "",
                     component_of(c.provides.target.refid)->address};
      uses_side.push_back(interface_call(ci));
      app_->connections.push_back(std::move(ci));
      continue;
    }
    if (c.provides.kind == profile::ProvidesEnd::Kind::Port) {
      auto provides =
          resolve_end(ci, c.provides.target, c.provides.port, profile::PortDirection::Provides);
      if (!provides)
        return tl::unexpected(provides.error());
      ci.provides = std::move(*provides);
    }
    if (!ci.uses.empty())
      uses_side.push_back(connect_call(ci, ci.uses, "uses"));
    if (!ci.provides.empty())
      provides_side.push_back(connect_call(ci, ci.provides, "provides"));
    app_->connections.push_back(std::move(ci));
  }
  // Devices outlive the application: their ends of its connections are undone on their own (the
  // components' ends go with their processes).
  saga_.on_undo([this] {
    const auto ends = ApplicationFactory(s_).disconnect_devices(*app_);
    return ends == 0 ? std::string()
                     : fmt::format("{} device end{} disconnected", ends, ends == 1 ? "" : "s");
  });
  // Readers first, so the first samples written find them.
  auto began = Clock::now();
  if (auto ok = call_all(*s_.endpoint, provides_side, s_.call_timeout); !ok)
    return ok;
  const double readers_ms = ms_since(began);
  began = Clock::now();
  if (auto ok = call_all(*s_.endpoint, uses_side, s_.call_timeout); !ok)
    return ok;
  const double writers_ms = ms_since(began);
  began = Clock::now();
  if (auto ok = await_matched(); !ok)
    return ok;
  detail_ = fmt::format("{} connections (readers {:.0f} ms, writers {:.0f} ms, matched {:.0f} ms)",
                        app_->connections.size(), readers_ms, writers_ms, ms_since(began));
  return {};
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

CallResult<void> ApplicationFactory::Launch::await_matched() {
  std::map<std::string, protocol::component::AwaitMatchedRequest> awaited; // by address
  auto await = [&](const ConnectionInstance &ci, const ConnectionEnd &end, int peers) {
    if (end.empty() || peers == 0)
      return;
    auto &request = awaited[end.address];
    request.timeout_ms = s_.call_timeout.count();
    request.connections.push_back({end.port, end_key(ci, end), peers, 0});
  };
  for (const auto &ci : app_->connections) {
    if (ci.is_interface())
      continue; // a control address: nothing to discover
    const bool channel = ci.uses.empty() || ci.provides.empty();
    await(ci, ci.uses, channel ? members_on(ci.topic, /*subscribers=*/true) : 1);
    await(ci, ci.provides, channel ? members_on(ci.topic, /*subscribers=*/false) : 1);
  }
  std::vector<Call> calls;
  for (auto &[address, request] : awaited)
    calls.push_back(call_of<protocol::component::AwaitMatched>(address, request, address));
  auto replies = call_each_of(*s_.endpoint, calls, 2 * s_.call_timeout);
  if (auto ok = first_failure(calls, replies); !ok)
    return ok;
  std::vector<std::string> unmatched;
  for (auto &raw : replies) {
    auto reply = control::reply_of<protocol::component::AwaitMatched>(std::move(raw));
    if (!reply)
      return tl::unexpected(reply.error());
    for (const auto &c : reply->connections)
      if (c.matched < c.peers)
        unmatched.push_back(fmt::format("{} on port {}: {} of {} peers matched", c.connection,
                                        c.port, c.matched, c.peers));
  }
  if (!unmatched.empty())
    return control::call_error(Status::Unavailable,
                               fmt::format("connections not matched after {} ms: {}",
                                           s_.call_timeout.count(), fmt::join(unmatched, "; ")));
  return {};
}

int ApplicationFactory::Launch::members_on(const std::string &topic, bool subscribers) const {
  int n = 0;
  for (const auto &ci : app_->connections)
    if (ci.topic == topic && !(subscribers ? ci.provides : ci.uses).empty())
      ++n;
  return n;
}

Call ApplicationFactory::Launch::connect_call(const ConnectionInstance &ci,
                                              const ConnectionEnd &end, const char *direction) {
  protocol::component::ConnectRequest request;
  request.connection = end_key(ci, end);
  request.port = end.port;
  request.direction = direction;
  request.topic = ci.topic;
  request.repid = ci.repid;
  request.qos = ci.qos;
  request.filter = std::string_view(direction) == "provides" ? ci.filter : "";
  request.local = in_one_host(ci);
  return call_of<protocol::component::Connect>(end.address, request,
                                               fmt::format("{} ({})", ci.id, end.name()));
}

Call ApplicationFactory::Launch::interface_call(const ConnectionInstance &ci) {
  protocol::component::ConnectRequest request;
  request.connection = end_key(ci, ci.uses);
  request.port = ci.uses.port;
  request.direction = "uses";
  request.repid = ci.repid;
  request.target = ci.provides.address;
  return call_of<protocol::component::Connect>(
      ci.uses.address, request,
      fmt::format("{} ({} -> {})", ci.id, ci.uses.name(), ci.provides.name()));
}

bool ApplicationFactory::Launch::in_one_host(const ConnectionInstance &ci) const {
  if (ci.uses.component.empty() || ci.provides.component.empty())
    return false;
  const auto *uses = component_of(ci.uses.component);
  const auto *provides = component_of(ci.provides.component);
  return uses != nullptr && provides != nullptr && !uses->host.empty() &&
         uses->host == provides->host;
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
