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
  switch (state) {
  case ComponentState::Allocated:
    return "allocated";
  case ComponentState::Executed:
    return "executed";
  case ComponentState::Registered:
    return "registered";
  case ComponentState::Running:
    return "running";
  case ComponentState::Stopped:
    return "stopped";
  case ComponentState::Exited:
    return "exited";
  case ComponentState::Released:
    return "released";
  }
  return "unknown";
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

std::vector<std::string> exited_components(const Application &app) {
  std::vector<std::string> ids;
  for (const auto &c : app.components)
    if (c.state == ComponentState::Exited)
      ids.push_back(c.id);
  return ids;
}

std::string state_of(const Application &app) {
  return exited_components(app).empty() ? std::string(to_string(app.state)) : "degraded";
}

nlohmann::json to_json(const Application &app) {
  nlohmann::json components = nlohmann::json::array();
  for (const auto &c : app.components) {
    nlohmann::json entry{{"id", c.id},
                         {"usage_name", c.usage_name},
                         {"node", c.node},
                         {"device", c.device},
                         {"implementation", c.implementation},
                         {"address", c.address},
                         {"pid", c.pid},
                         {"state", to_string(c.state)},
                         {"assembly_controller", c.assembly_controller}};
    for (const auto &p : app.plan.placements)
      if (p.instance == c.id && p.schedule)
        entry["schedule"] = allocator::to_json(*p.schedule);
    components.push_back(std::move(entry));
  }
  nlohmann::json connections = nlohmann::json::array();
  for (const auto &c : app.connections)
    connections.push_back({{"id", c.id},
                           {"uses", c.uses.name()},
                           {"provides", c.provides.name()},
                           {"repid", c.repid},
                           {"topic", c.topic},
                           {"qos", c.qos}});
  return {
      {"name", app.name},          {"installed", app.installed},       {"sad", app.sad},
      {"state", state_of(app)},    {"exited", exited_components(app)}, {"components", components},
      {"connections", connections}};
}

} // namespace rsca::domain
