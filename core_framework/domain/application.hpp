// A running application as the domain holds it: where each component runs, how they are wired,
// and what was reserved for them.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "allocator/resource_allocator.hpp"
#include "profile/profile_loader.hpp"

namespace rsca::domain {

enum class ApplicationState : std::uint8_t { Created, Running, Stopped, Failed };
std::string_view to_string(ApplicationState state);

struct ComponentInstance {
  std::string id; // componentinstantiation id
  std::string usage_name;
  std::string node;
  std::string device;
  std::string implementation;
  std::string address; // its control endpoint
  std::string spd;     // the SPD it runs from
  long pid = 0;
  std::string state; // "executed", "registered", "running", "stopped", "exited"
  std::uint32_t start_order = 0;
  bool assembly_controller = false;
};

struct ConnectionEnd {
  std::string component;
  std::string port;
};

struct ConnectionInstance {
  std::string id;
  ConnectionEnd uses;
  ConnectionEnd provides;
  std::string repid;
  std::string topic;
  nlohmann::json qos;
  std::string filter; // a channel subscriber's content filter
};

struct Application {
  std::string name;      // instance name, unique in the domain
  std::string installed; // the installed application it was created from
  std::string sad;       // path of the SAD
  ApplicationState state = ApplicationState::Created;
  std::vector<ComponentInstance> components;
  std::vector<ConnectionInstance> connections;
  allocator::Plan plan; // what the allocator placed and reserved
  std::shared_ptr<const profile::ResolvedApplication> profile;

  ComponentInstance *find_component(std::string_view id);
  const ComponentInstance *find_component(std::string_view id) const;
};

nlohmann::json to_json(const Application &app);

} // namespace rsca::domain
