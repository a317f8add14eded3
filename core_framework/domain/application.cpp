#include "domain/application.hpp"

#include "allocator/plan_json.hpp"

namespace rsca::domain {

std::string_view to_string(ApplicationState state) {
  switch (state) {
  case ApplicationState::Created:
    return "created";
  case ApplicationState::Running:
    return "running";
  case ApplicationState::Stopped:
    return "stopped";
  case ApplicationState::Failed:
    return "failed";
  }
  return "unknown";
}

std::string_view to_string(ComponentState state) {
  return protocol::enum_name(state);
}

ComponentInstance *Application::find_component(std::string_view id) {
  for (auto &c : components)
    if (c.id == id)
      return &c;
  return nullptr;
}

const ComponentInstance *Application::find_component(std::string_view id) const {
  for (const auto &c : components)
    if (c.id == id)
      return &c;
  return nullptr;
}

namespace {
std::vector<std::string> components_in(const Application &app, ComponentState state) {
  std::vector<std::string> ids;
  for (const auto &c : app.components)
    if (c.state == state)
      ids.push_back(c.id);
  return ids;
}
} // namespace

std::vector<std::string> exited_components(const Application &app) {
  return components_in(app, ComponentState::Exited);
}

std::vector<std::string> unreachable_components(const Application &app) {
  return components_in(app, ComponentState::Unreachable);
}

std::string state_of(const Application &app) {
  const bool whole = exited_components(app).empty() && unreachable_components(app).empty();
  return whole ? std::string(to_string(app.state)) : "degraded";
}

namespace {

namespace app_ops = protocol::application;

app_ops::ComponentView view_of(const Application &app, const ComponentInstance &c) {
  app_ops::ComponentView view{
      c.id,    c.usage_name,          c.node,      c.device, c.implementation, c.address, c.pid,
      c.state, c.assembly_controller, std::nullopt};
  for (const auto &p : app.plan.placements)
    if (p.instance == c.id && p.schedule)
      view.schedule = allocator::to_json(*p.schedule);
  return view;
}

// An end as a typed port; none for an event channel's side.
std::optional<protocol::connection::PortEnd> port_of(const Application &app,
                                                     const ConnectionEnd &end) {
  if (end.empty())
    return std::nullopt;
  if (!end.device.empty())
    return protocol::connection::PortEnd{std::nullopt, std::nullopt, end.device, end.port};
  return protocol::connection::PortEnd{app.name, end.component, std::nullopt, end.port};
}

std::optional<std::string> unless_empty(const std::string &text) {
  return text.empty() ? std::nullopt : std::optional(text);
}

app_ops::SadConnectionView view_of(const Application &app, const ConnectionInstance &c) {
  app_ops::SadConnectionView view;
  view.id = c.id;
  view.uses = c.uses.name();
  view.provides = c.provides.name();
  view.repid = c.repid;
  view.topic = c.topic;
  view.qos = c.qos;
  view.uses_end = port_of(app, c.uses);
  view.provides_end = port_of(app, c.provides);
  view.channel = unless_empty(c.channel);
  view.filter = unless_empty(c.filter);
  return view;
}

std::string_view kind_name(profile::ExternalPort::Kind kind) {
  switch (kind) {
  case profile::ExternalPort::Kind::Uses:
    return "uses";
  case profile::ExternalPort::Kind::Provides:
    return "provides";
  case profile::ExternalPort::Kind::SupportedInterface:
    return "supportedinterface";
  }
  return "unknown";
}

std::vector<app_ops::ExternalPortView> external_ports_of(const Application &app) {
  std::vector<app_ops::ExternalPortView> ports;
  if (!app.profile || !app.profile->sad)
    return ports;
  for (const auto &p : app.profile->sad->external_ports)
    ports.push_back({p.external_name, p.component_ref, p.port, std::string(kind_name(p.kind))});
  return ports;
}

} // namespace

app_ops::ApplicationView view_of(const Application &app) {
  app_ops::ApplicationView view;
  view.name = app.name;
  view.installed = app.installed;
  view.sad = app.sad;
  view.state = state_of(app);
  view.exited = exited_components(app);
  for (const auto &c : app.components)
    view.components.push_back(view_of(app, c));
  for (const auto &c : app.connections)
    view.connections.push_back(view_of(app, c));
  view.external_ports = external_ports_of(app);
  return view;
}

} // namespace rsca::domain
