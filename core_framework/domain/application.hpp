// A running application as the domain holds it: where each component runs, how they are wired,
// and what was reserved for them.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "allocator/resource_allocator.hpp"
#include "profile/profile_loader.hpp"
#include "protocol/application_ops.hpp"

namespace rsca::domain {

enum class ApplicationState : std::uint8_t { Created, Running, Stopped, Failed };
std::string_view to_string(ApplicationState state);

// A component's life as the domain sees it (protocol/application_ops.hpp: users see it).
using ComponentState = protocol::application::ComponentState;
std::string_view to_string(ComponentState state);

struct ComponentInstance {
  std::string id; // componentinstantiation id
  std::string usage_name;
  std::string node;
  std::string device;
  std::string implementation;
  std::string address; // its control endpoint
  std::string host;    // the address of the component host that serves it, if it is hosted
  std::string via;     // the endpoint that serves its address (its node or host); empty: itself
  std::string spd;     // the SPD it runs from
  long pid = 0;
  // Where its process began writing its log on its node (ExecuteReply), for app.failed.
  std::optional<std::uint64_t> log_offset{};
  ComponentState state = ComponentState::Allocated;
  ComponentState state_before_lost = ComponentState::Allocated; // restored when its node is back
  std::uint32_t start_order = 0;
  bool assembly_controller = false;
  // The node that relays to its process (which that node started); empty when none does.
  std::string relaying_node() const { return via != host ? via : std::string(); }
};

// One end of a connection: a port of a component of the application, or of a device (which
// outlives the application: its end is disconnected when the application goes).
struct ConnectionEnd {
  std::string component; // the component instantiation, or empty for a device
  std::string port;
  std::string device;  // the device's id, for a device port
  std::string address; // where the port's owner is served
  bool empty() const { return component.empty() && device.empty(); }
  // "owner.port"; the owner alone for a component's supported interface (no port).
  std::string name() const {
    if (empty())
      return {};
    const std::string &owner = device.empty() ? component : device;
    return port.empty() ? owner : owner + "." + port;
  }
};

struct ConnectionInstance {
  std::string id;
  ConnectionEnd uses;
  ConnectionEnd provides;
  std::string repid;
  std::string topic;
  nlohmann::json qos;
  std::string filter;  // a channel subscriber's content filter
  std::string channel; // the event channel a member joins; empty: none
  // A uses port's connection to a component's supported interface: no topic, the provides end
  // is the component itself.
  bool is_interface() const { return topic.empty() && !provides.empty() && provides.port.empty(); }
};

// The id an end's owner knows the connection by: a device serves many applications, so its
// connections go by their topic, unique in the domain; a component's by the SAD's id.
inline const std::string &end_key(const ConnectionInstance &c, const ConnectionEnd &end) {
  return end.device.empty() ? c.id : c.topic;
}

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

// The ids of the components that exited while the application ran.
std::vector<std::string> exited_components(const Application &app);
// Those on a node that is lost (they may still run).
std::vector<std::string> unreachable_components(const Application &app);
// The application's state as users see it: "degraded" once a component has exited (until it is
// released), else its lifecycle state.
std::string state_of(const Application &app);

// The application as replies show it (its connections without their live state).
protocol::application::ApplicationView view_of(const Application &app);

} // namespace rsca::domain
