// Internal to the DomainManager: its parts and the operations it serves, shared by the files that
// implement them (domain_manager.cpp: installs and applications; domain_connections.cpp: nodes,
// devices, connections and channels). Each part owns its state and its lock: the installed
// applications (InstalledRepository), the running ones (ApplicationRegistry), the nodes (below),
// runtime connections (ConnectionManager), event channels (EventChannelManager).
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>

#include <fmt/format.h>

#include "control/domain_events.hpp"
#include "domain/application_registry.hpp"
#include "domain/connection_manager.hpp"
#include "domain/domain_manager.hpp"
#include "domain/installed_repository.hpp"
#include "domain/launch_tracker.hpp"
#include "domain/node_directory.hpp"
#include "protocol/domain_ops.hpp"

namespace rsca::domain {

using control::CallResult;

// A component process found running that no application of this domain daemon launched: left by
// a domain daemon that was killed, or by another domain on the same DDS domain and tag.
struct UnknownComponent {
  std::string address;
  control::Json announcement;
};

struct DomainManager::Impl {
  DomainOptions options;
  std::shared_ptr<dds::Participant> participant;
  std::unique_ptr<control::Endpoint> endpoint;
  allocator::ResourceAllocator allocator;
  ComponentRegistry components;
  std::unique_ptr<control::DomainEvents> events;
  std::optional<ConnectionManager> runtime_connections; // made before the endpoint opens
  std::optional<EventChannelManager> channels;          // made when the domain's name is known
  std::optional<DomainStore> store;
  std::optional<InstalledRepository> repository;
  ApplicationRegistry applications;
  LaunchTracker launches;
  std::uint64_t incarnation = 0; // this run of the daemon, counted in the store
  std::atomic<std::uint64_t> launch_counter{0};
  // Held while an uninstall checks for launches of the application and removes it, and while a
  // launch finds its installed application and reserves its name: neither slips between the
  // other's two steps.
  std::mutex installs;
  std::mutex kept_connections; // a runtime connection and its record in the store change together

  NodeDirectory nodes;
  std::mutex unknown_mutex; // guards unknown
  std::map<std::string, UnknownComponent> unknown;

  ApplicationFactory factory();
  // Runs a change of `name`'s state under the registry's lock (ApplicationFactory::ApplyChange).
  ApplicationFactory::ApplyChange apply_to(const std::string &name);

  // Installs and applications (domain_manager.cpp).
  CallResult<control::Json> install(const control::Json &body);
  CallResult<control::Json> uninstall(const control::Json &body);
  CallResult<control::Json> list_installed();
  CallResult<control::Json> create_application(const control::Json &body);
  CallResult<std::shared_ptr<Application>>
  launch(LaunchRequest &request, const std::string &launch_id, std::vector<LaunchStep> &steps);
  CallResult<control::Json> progress(const control::Json &body);
  CallResult<control::Json> cancel_launch(const control::Json &body);
  CallResult<control::Json> release(const control::Json &body);
  CallResult<control::Json> start_or_stop(const control::Json &body, bool start);
  CallResult<control::Json> configure(const control::Json &body);
  CallResult<control::Json> query(const control::Json &body);
  CallResult<control::Json> configure_at(const std::string &address, control::Json properties);
  CallResult<control::Json> query_at(const std::string &address, std::vector<std::string> ids);
  CallResult<control::Json> list_applications();
  CallResult<control::Json> show_application(const control::Json &body);
  CallResult<control::Json> plan_application(const control::Json &body);
  CallResult<protocol::Empty> component_exited(const protocol::domain::ComponentExitedReport &r);
  CallResult<protocol::Empty>
  connection_problem(const protocol::domain::ConnectionProblemReport &r);
  // Marks the running components `which` selects as exited.
  void mark_exited(const std::function<bool(const ComponentInstance &)> &which,
                   const std::string &why);
  void serve();

  // Nodes, devices, connections and channels (domain_connections.cpp).
  void on_announcement(const control::AnnouncementEvent &event);
  void node_alive(const control::AnnouncementEvent &event);
  void node_gone(const std::string &address);
  void component_announced(const control::AnnouncementEvent &event);
  CallResult<std::string> device_address(const std::string &id);
  CallResult<ResolvedEnd> resolve_end(const PortRef &ref, profile::PortDirection direction);
  CallResult<ResolvedEnd> resolve_component_end(const PortRef &ref,
                                                profile::PortDirection direction);
  CallResult<ResolvedEnd> resolve_device_end(const PortRef &ref, profile::PortDirection direction);
  CallResult<control::Json> list_nodes();
  CallResult<control::Json> list_devices();
  CallResult<control::Json> list_channels();
  CallResult<control::Json> create_channel(const control::Json &body);
  CallResult<control::Json> destroy_channel(const control::Json &body);
  CallResult<control::Json> list_connections(const control::Json &body);
  CallResult<control::Json> create_connection(const control::Json &body);
  CallResult<control::Json> destroy_connection(const control::Json &body);
  CallResult<RuntimeConnection> make_connection(const control::Json &body);
  void restore_connections();
  control::Json unknown_components();
};

// A required field of a request, typed; a clear BadRequest when it is missing or of another type.
template <typename T>
control::CallResult<T> required(const control::Json &body, const char *key) {
  if (!body.contains(key))
    return control::call_error(control::Status::BadRequest,
                               fmt::format("the request has no \"{}\"", key));
  try {
    return body.at(key).get<T>();
  } catch (const control::Json::exception &) {
    return control::call_error(control::Status::BadRequest,
                               fmt::format("\"{}\" has the wrong type", key));
  }
}

// A field that may be absent; of the wrong type it is a BadRequest.
template <typename T>
control::CallResult<std::optional<T>> optional_field(const control::Json &body, const char *key) {
  if (!body.contains(key))
    return std::optional<T>();
  auto value = required<T>(body, key);
  if (!value)
    return tl::unexpected(value.error());
  return std::optional<T>(std::move(*value));
}

} // namespace rsca::domain
