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

protocol::application::ApplicationView view_of(const Application &app) {
  protocol::application::ApplicationView view{
      app.name, app.installed, app.sad, state_of(app), exited_components(app), {}, {}};
  for (const auto &c : app.components) {
    protocol::application::ComponentView component{
        c.id,    c.usage_name,          c.node,      c.device, c.implementation, c.address, c.pid,
        c.state, c.assembly_controller, std::nullopt};
    for (const auto &p : app.plan.placements)
      if (p.instance == c.id && p.schedule)
        component.schedule = allocator::to_json(*p.schedule);
    view.components.push_back(std::move(component));
  }
  for (const auto &c : app.connections)
    view.connections.push_back({c.id, c.uses.name(), c.provides.name(), c.repid, c.topic, c.qos});
  return view;
}

} // namespace rsca::domain
