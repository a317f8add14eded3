// The DomainManager's devices, connections and channels: what components
// announce, where a connection's end is served, the connections' live state, runtime connections
// kept across restarts, and event channels.
#include <unistd.h>

#include <algorithm>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "allocator/plan_json.hpp"
#include "common/host_name.hpp"
#include "common/names.hpp"
#include "control/operation.hpp"
#include "domain/domain_manager_impl.hpp"
#include "protocol/component_ops.hpp"

namespace rsca::domain {
namespace {

using control::Json;
using control::Status;

using StatusOf = std::map<std::string, protocol::component::StatusReply>; // by address

// One end's live state from its owner's status: {"matched", "samples", "filtered", ...}, or
// null.
Json end_state(const StatusOf &status_of, const std::string &address, const std::string &port_name,
               const std::string &connection) {
  auto it = status_of.find(address);
  if (address.empty() || it == status_of.end())
    return nullptr;
  for (const auto &port : it->second.ports) {
    if (port.name != port_name)
      continue;
    for (const auto &c : port.connections) {
      if (c.connection != connection)
        continue;
      if (c.calls)
        return Json{{"calls", *c.calls}}; // a caller of a supported interface
      Json state{{"matched", c.matched.value_or(0)},
                 {"samples", c.samples.value_or(0)},
                 {"filtered", c.filtered.value_or(0)},
                 {"deadline_missed", c.deadline_missed.value_or(0)},
                 {"in_host", c.in_host.value_or(false)},
                 {"same_host", c.same_host.value_or(false)},
                 {"relayed", c.relayed.value_or(false)},
                 {"tcp", c.tcp.value_or(false)}};
      if (c.deadline_ns)
        state["deadline_ns"] = *c.deadline_ns; // the deadline the end applies
      if (c.qos)
        state["qos"] = protocol::encode(*c.qos); // as the end's live transport applies it
      return state;
    }
  }
  return nullptr;
}

// An application's connection in connection.list, with its ends' live state.
connection_ops::ListedConnection listed(const Application &app, const ConnectionInstance &c,
                                        const StatusOf &status_of) {
  auto state = [&](const ConnectionEnd &e) {
    return end_state(status_of, e.address, e.port, end_key(c, e));
  };
  return {{c.id, c.uses.name(), c.provides.name(), c.topic, c.repid, c.qos},
          app.name,
          c.filter,
          std::nullopt,
          std::nullopt,
          state(c.uses),
          state(c.provides)};
}

connection_ops::ConnectionView view_of(const RuntimeConnection &c) {
  return {c.id, c.uses.to_string(), c.provides.to_string(), c.topic, c.repid, c.qos};
}

connection_ops::ConnectionState state_of(const RuntimeConnection &c) {
  return c.connected() ? connection_ops::ConnectionState::Connected
                       : connection_ops::ConnectionState::Pending;
}

// A runtime connection's content filter, when it has one.
std::optional<std::string> filter_of(const RuntimeConnection &c) {
  return c.filter.empty() ? std::nullopt : std::optional(c.filter);
}

// What a pending connection waits for; nothing for a connected one.
std::optional<std::string> waiting_for(const RuntimeConnection &c) {
  return c.connected() ? std::nullopt : std::optional(c.waiting_for);
}

// A runtime connection in connection.list: its ends' live state only when it is connected.
connection_ops::ListedConnection listed(const RuntimeConnection &c, const StatusOf &status_of) {
  auto state = [&](const ResolvedEnd &end) {
    return c.connected() ? end_state(status_of, end.address, end.port, c.id) : Json();
  };
  return {view_of(c),     "(runtime)",       filter_of(c),         state_of(c),
          waiting_for(c), state(c.uses_end), state(c.provides_end)};
}

connection_ops::ChannelView view_of(const EventChannel &channel) {
  connection_ops::ChannelView view{
      channel.name, channel.topic, channel.repid, channel.operator_owned, 0, 0, {}};
  for (const auto &m : channel.members) {
    view.publishers += m.role == ChannelMember::Role::Publisher ? 1 : 0;
    view.members.push_back({std::string(to_string(m.role)), m.application, m.connection,
                            m.component, m.port, m.filter});
  }
  view.subscribers = channel.members.size() - view.publishers;
  return view;
}

// {"application", "component", "port"}, {"application", "port"} (an external port) or
// {"device", "port"}.
CallResult<PortRef> port_ref(const connection_ops::PortEnd &end, const char *key) {
  PortRef ref;
  ref.port = end.port;
  if (end.device) {
    ref.kind = PortRef::Kind::Device;
    ref.owner = *end.device;
  } else {
    ref.owner = end.application.value_or("");
    ref.component = end.component.value_or("");
    ref.kind = ref.component.empty() ? PortRef::Kind::External : PortRef::Kind::Component;
  }
  if (ref.owner.empty() || ref.port.empty())
    return control::call_error(
        Status::BadRequest,
        fmt::format("\"{}\" needs a port and an application (with a component) or a device", key));
  return ref;
}

// The addresses whose status shows the state of `app`'s connections: its components that have
// not exited (one that exited cannot answer) and the devices its connections reach.
void status_addresses(const Application &app, std::set<std::string> &addresses) {
  for (const auto &c : app.components)
    if (c.state != ComponentState::Exited && c.state != ComponentState::Unreachable)
      addresses.insert(c.address);
  for (const auto &c : app.connections)
    for (const auto *end : {&c.uses, &c.provides})
      if (!end->device.empty() && !end->address.empty())
        addresses.insert(end->address);
}

// One status call to every address at once, bounded by `timeout`: the statuses of those that
// answered.
StatusOf statuses_of(control::Endpoint &endpoint, const std::set<std::string> &addresses,
                     std::chrono::milliseconds timeout) {
  std::vector<control::Call> calls;
  for (const auto &address : addresses)
    calls.push_back(control::make_call<protocol::component::Status>(address, {}));
  const auto statuses = endpoint.call_all(calls, timeout);
  StatusOf status_of;
  for (std::size_t i = 0; i < calls.size(); ++i)
    if (auto status = control::reply_of<protocol::component::Status>(statuses[i]))
      status_of[calls[i].target] = std::move(*status);
  return status_of;
}

// An end's component is gone: its process exited, or its node is lost.
bool owner_gone(const Application &app, const ConnectionEnd &end) {
  const auto *component = end.component.empty() ? nullptr : app.find_component(end.component);
  return component != nullptr && (component->state == ComponentState::Exited ||
                                  component->state == ComponentState::Unreachable);
}

// A SAD connection's live state from its ends' owners: failed when an owner is gone; pending
// while an end has not matched its peer (a channel's member alone on its channel); connected
// when every end has; none when an end did not answer. The component a uses port calls through
// its supported interface reports nothing of it: only its caller counts.
std::optional<connection_ops::ConnectionState>
live_state(const Application &app, const ConnectionInstance &c, const StatusOf &status_of) {
  using State = connection_ops::ConnectionState;
  bool matched = true;
  for (const auto *end : {&c.uses, &c.provides}) {
    if (end->empty())
      continue; // the event channel's side
    if (owner_gone(app, *end))
      return State::Failed;
    if (c.is_interface() && end == &c.provides)
      continue;
    const Json state = end_state(status_of, end->address, end->port, end_key(c, *end));
    if (state.is_null())
      return std::nullopt;
    matched = matched && (state.contains("calls") || state.value("matched", 0) > 0);
  }
  return matched ? State::Connected : State::Pending;
}

// A runtime connection's request as the domain's store keeps it (with "format": 1).
CallResult<connection_ops::CreateRequest> kept_request(const std::string &text) {
  Json record = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (!record.is_object())
    return control::call_error(Status::BadRequest, "not JSON");
  if (record.value("format", 0) != 1)
    return control::call_error(Status::BadRequest, "kept in another format");
  record.erase("format");
  auto request = protocol::decode<connection_ops::CreateRequest>(record);
  if (!request)
    return control::call_error(Status::BadRequest, request.error());
  return std::move(*request);
}

} // namespace

void DomainManager::Impl::on_announcement(const control::AnnouncementEvent &event) {
  using Kind = control::AnnouncementEvent::Kind;
  if (event.kind == Kind::Alive && event.endpoint_kind == "node")
    return node_alive(event);
  if (event.kind == Kind::Alive && event.endpoint_kind == "component")
    return component_announced(event);
  if (event.kind != Kind::Gone)
    return;
  components.gone(event.address);
  node_gone(event.address, event.withdrawn);
}

// A component announced itself. One that an earlier run of this domain daemon launched (its
// address carries another incarnation) is running without an application this run knows: it is
// reported, once, and never taken for a component of a launch of this run. An announcement that
// does not decode breaks the contract: the component is taken for exited, with why, so that a
// launch waiting for it fails at once and names the field.
void DomainManager::Impl::component_announced(const control::AnnouncementEvent &event) {
  auto announced = protocol::decode<protocol::component::Announcement>(event.body);
  if (!announced) {
    const auto why = fmt::format("its announcement is not taken: {}", announced.error());
    spdlog::warn("component {}: {}", excerpt(event.address), why);
    components.exited(event.address, why);
    return;
  }
  const auto launched_by = protocol::incarnation_of(event.address);
  if (!launched_by || *launched_by == incarnation) {
    components.announced(event.address);
    return;
  }
  std::lock_guard lock(unknown_mutex);
  const bool first = unknown.count(event.address) == 0;
  unknown[event.address] = {event.address, std::move(*announced)};
  if (!first)
    return;
  const auto &a = unknown[event.address].announcement;
  spdlog::warn("component {} (pid {}) runs but no application of this domain daemon launched "
               "it: an earlier run (incarnation {}, this one is {}) did; stop it by hand or "
               "restart its node",
               event.address, a.pid, *launched_by, incarnation);
  events->publish("component.unknown", {{"address", event.address},
                                        {"application", a.application},
                                        {"component", a.id},
                                        {"pid", a.pid}});
}

std::vector<app_ops::UnknownComponent> DomainManager::Impl::unknown_components() {
  std::lock_guard lock(unknown_mutex);
  std::vector<app_ops::UnknownComponent> list;
  for (const auto &[address, u] : unknown)
    list.push_back({address, u.announcement.application, u.announcement.id, u.announcement.pid});
  return list;
}

// A device's control address, for "device" requests of app.configure and app.query.
CallResult<std::string> DomainManager::Impl::device_address(const std::string &id) {
  const auto device = nodes.device(id);
  if (!device)
    return control::call_error(Status::NotFound,
                               fmt::format("no device {} has registered", excerpt(id)));
  if (device->address.empty())
    return control::call_error(Status::NotFound,
                               fmt::format("device {} has no properties to reach", id));
  return device->address;
}

CallResult<ResolvedEnd> DomainManager::Impl::resolve_end(const PortRef &ref,
                                                         profile::PortDirection direction) {
  return ref.kind == PortRef::Kind::Device ? resolve_device_end(ref, direction)
                                           : resolve_component_end(ref, direction);
}

CallResult<ResolvedEnd>
DomainManager::Impl::resolve_component_end(const PortRef &ref, profile::PortDirection direction) {
  const bool uses = direction == profile::PortDirection::Uses;
  auto found = applications.snapshot(ref.owner);
  if (!found)
    return control::call_error(Status::Unavailable,
                               fmt::format("application {} is not running", ref.owner));
  const Application &app = *found;
  std::string component = ref.component, port = ref.port;
  if (ref.kind == PortRef::Kind::External) {
    const auto wanted =
        uses ? profile::ExternalPort::Kind::Uses : profile::ExternalPort::Kind::Provides;
    const profile::ExternalPort *external = nullptr;
    for (const auto &e : app.profile->sad->external_ports)
      if (e.external_name == ref.port && e.kind == wanted)
        external = &e;
    if (external == nullptr)
      return control::call_error(Status::NotFound,
                                 fmt::format("{} is not an external {} port", ref.to_string(),
                                             profile::to_string(direction)));
    component = external->component_ref;
    port = external->port;
  }
  const auto *instance = app.find_component(component);
  if (instance == nullptr)
    return control::call_error(
        Status::NotFound, fmt::format("application {} has no component {}", ref.owner, component));
  const profile::ComponentPlacement *placement = nullptr;
  app.profile->sad->find_instantiation(component, &placement);
  const auto *pkg = placement != nullptr ? app.profile->softpkg_of(*placement) : nullptr;
  const auto *definition =
      pkg != nullptr && pkg->scd ? pkg->scd->find_port(port, direction) : nullptr;
  if (definition == nullptr)
    return control::call_error(Status::NotFound, fmt::format("{} is not a {} port", ref.to_string(),
                                                             profile::to_string(direction)));
  return ResolvedEnd{instance->address, port, definition->repid, instance->host,
                     instance->relaying_node()};
}

CallResult<ResolvedEnd> DomainManager::Impl::resolve_device_end(const PortRef &ref,
                                                                profile::PortDirection direction) {
  const auto wanted = profile::to_string(direction);
  const std::string node = ref.owner.substr(0, ref.owner.find(':'));
  if (!nodes.contains(node))
    return control::call_error(Status::Unavailable,
                               fmt::format("device {} has not registered", ref.owner));
  const auto device = nodes.device(ref.owner);
  if (!device)
    return control::call_error(Status::NotFound,
                               fmt::format("node {} has no device {}", node, ref.owner));
  for (const auto &p : device->ports)
    if (p.name == ref.port && p.direction == wanted)
      return ResolvedEnd{device->address, ref.port, p.repid, "", ""};
  return control::call_error(Status::NotFound,
                             fmt::format("{} is not a {} port", ref.to_string(), wanted));
}

namespace {

domain_ops::NodeSummary summary_of(const NodeDirectory::Node &node) {
  const auto &a = node.announcement;
  return {a.node, node.address, a.pid, a.devices.size(), a.failed_devices};
}

} // namespace

// A lost node is listed apart, not left out: it still holds its devices' reservations and its
// components, and may come back; `rsca ls nodes` and `rsca top` show it as lost.
CallResult<domain_ops::NodesReply> DomainManager::Impl::list_nodes() {
  domain_ops::NodesReply reply;
  for (const auto &node : nodes.snapshot())
    reply.nodes.push_back(summary_of(node));
  for (const auto &r : nodes.refused_nodes())
    reply.refused.push_back({excerpt(r.address), r.why});
  for (const auto &node : nodes.lost_nodes())
    reply.lost.push_back(summary_of(node));
  return reply;
}

CallResult<domain_ops::DevicesReply> DomainManager::Impl::list_devices() {
  return domain_ops::DevicesReply{allocator::to_json(allocator.snapshot())};
}

CallResult<domain_ops::TopReply> DomainManager::Impl::top() {
  const auto self = ::getpid();
  auto own = sampler.read(self);
  if (!own)
    return control::call_error(Status::Failed, "cannot read the domain's own /proc figures");
  return domain_ops::TopReply{host_name(), {self, own->cpu_percent, own->rss_bytes, own->threads}};
}

CallResult<connection_ops::ChannelsReply> DomainManager::Impl::list_channels() {
  connection_ops::ChannelsReply reply;
  for (const auto &c : channels->list())
    reply.channels.push_back(view_of(c));
  return reply;
}

CallResult<connection_ops::ChannelView>
DomainManager::Impl::create_channel(const domain_ops::Named &request) {
  return channels->create(request.name).map([](const EventChannel &c) { return view_of(c); });
}

CallResult<domain_ops::Named>
DomainManager::Impl::destroy_channel(const domain_ops::Named &request) {
  if (auto ok = channels->destroy(request.name); !ok)
    return tl::unexpected(ok.error());
  return request;
}

// Every connection of the running applications (or of one), with its live state as its
// components report it: matched or not, samples through it. The domain answers with what it
// knows: one status call to every live owner at once, bounded below the CLI's own wait; an end
// whose owner exited or does not answer shows no state.
CallResult<connection_ops::ListReply>
DomainManager::Impl::list_connections(const connection_ops::ListRequest &request) {
  const std::string &only = request.app;
  std::vector<Application> apps = applications.snapshots();
  std::erase_if(apps, [&](const Application &a) { return !only.empty() && a.name != only; });
  if (!only.empty() && apps.empty())
    return control::call_error(Status::NotFound,
                               fmt::format("no application {} runs", excerpt(only)));
  auto runtime = runtime_connections->list();
  std::erase_if(runtime, [&](const RuntimeConnection &c) {
    return !only.empty() && c.uses.owner != only && c.provides.owner != only;
  });
  std::set<std::string> addresses;
  for (const auto &app : apps)
    status_addresses(app, addresses);
  for (const auto &c : runtime)
    if (c.connected())
      addresses.insert({c.uses_end.address, c.provides_end.address});
  const auto status_of = statuses_of(*endpoint, addresses, options.call_timeout / 2);
  connection_ops::ListReply reply;
  for (const auto &app : apps)
    for (const auto &c : app.connections)
      reply.connections.push_back(listed(app, c, status_of));
  for (const auto &c : runtime)
    reply.connections.push_back(listed(c, status_of));
  return reply;
}

// As connection.list, the domain asks the live owners at once, bounded below the CLI's wait.
app_ops::ApplicationView DomainManager::Impl::live_view_of(const Application &app) {
  std::set<std::string> addresses;
  status_addresses(app, addresses);
  const auto status_of = statuses_of(*endpoint, addresses, options.call_timeout / 2);
  auto view = view_of(app);
  for (std::size_t i = 0; i < app.connections.size(); ++i)
    view.connections[i].state = live_state(app, app.connections[i], status_of);
  return view;
}

CallResult<RuntimeConnection>
DomainManager::Impl::make_connection(const connection_ops::CreateRequest &request) {
  auto uses = port_ref(request.uses, "uses");
  if (!uses)
    return tl::unexpected(uses.error());
  auto provides = port_ref(request.provides, "provides");
  if (!provides)
    return tl::unexpected(provides.error());
  return runtime_connections->connect(
      {*uses, *provides, request.id.value_or(""), request.qos, request.filter.value_or("")});
}

// A runtime connection lasts until `rsca disconnect`, also over a restart of the domain daemon:
// it is kept in the domain's store as its request.
CallResult<connection_ops::CreateReply>
DomainManager::Impl::create_connection(const connection_ops::CreateRequest &request) {
  // Made and kept as one step, so that a disconnect of the same id cannot come in between.
  std::lock_guard kept_lock(kept_connections);
  auto made = make_connection(request);
  if (!made)
    return tl::unexpected(made.error());
  // The request as given (the QoS asked for, not today's defaults), with the id it got.
  connection_ops::CreateRequest kept_as = request;
  kept_as.id = made->id;
  Json record = protocol::encode(kept_as);
  record["format"] = 1;
  connection_ops::CreateReply reply{view_of(*made), state_of(*made), waiting_for(*made), true,
                                    filter_of(*made)};
  if (auto kept = store->put_connection({made->id, record.dump()}); !kept) {
    spdlog::warn("runtime connection {} will not outlast a restart of the domain daemon: {}",
                 made->id, kept.error().to_string());
    reply.persisted = false;
  }
  return reply;
}

// The runtime connections of before a restart, made again: pending until their ends appear.
void DomainManager::Impl::restore_connections() {
  auto records = store->connections();
  if (!records) {
    spdlog::warn("runtime connections not restored: {}", records.error().to_string());
    return;
  }
  for (const auto &r : *records) {
    auto request = kept_request(r.request);
    auto made = request ? make_connection(*request) : tl::unexpected(request.error());
    if (!made) {
      spdlog::warn("runtime connection {} not restored ({}); `rsca disconnect {}` forgets it", r.id,
                   made.error().message, r.id);
      continue;
    }
    spdlog::info("runtime connection {} restored: {} -> {}{}", r.id, made->uses.to_string(),
                 made->provides.to_string(), made->connected() ? "" : " (pending)");
  }
}

CallResult<connection_ops::ConnectionId>
DomainManager::Impl::destroy_connection(const connection_ops::ConnectionId &request) {
  const std::string &id = request.id;
  std::lock_guard kept_lock(kept_connections);
  // Forgotten also when not made now: a kept request that no longer restores is removed so.
  auto forgotten = store->remove_connection(id);
  if (!forgotten)
    spdlog::warn("runtime connection {}: it may come back after a restart of the domain daemon: "
                 "{}",
                 id, forgotten.error().to_string());
  if (auto ok = runtime_connections->disconnect(id); !ok)
    return tl::unexpected(ok.error());
  return request;
}

} // namespace rsca::domain
