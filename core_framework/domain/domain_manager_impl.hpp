// Internal to the DomainManager: its parts and the operations it serves, shared by the files that
// implement them (domain_manager.cpp: installs and applications; domain_nodes.cpp: nodes that
// announce themselves, are lost and are back; domain_connections.cpp: devices, connections and
// channels). Each part owns its state and its lock: the installed applications
// (InstalledRepository), the running ones (ApplicationRegistry), the nodes (below), runtime
// connections (ConnectionManager), event channels (EventChannelManager).
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "control/domain_events.hpp"
#include "control/operation.hpp"
#include "control/worker_pool.hpp"
#include "domain/application_registry.hpp"
#include "domain/connection_manager.hpp"
#include "domain/domain_manager.hpp"
#include "domain/file_manager.hpp"
#include "domain/installed_repository.hpp"
#include "domain/launch_tracker.hpp"
#include "domain/node_directory.hpp"
#include "process/proc_figures.hpp"
#include "protocol/application_ops.hpp"
#include "protocol/component_ops.hpp"
#include "protocol/connection_ops.hpp"
#include "protocol/domain_ops.hpp"
#include "protocol/file_ops.hpp"

namespace rsca::domain {

using control::CallResult;
namespace app_ops = protocol::application;
namespace connection_ops = protocol::connection;
namespace domain_ops = protocol::domain;

// A component process found running that no application of this domain daemon launched: left by
// a domain daemon that was killed, or by another domain on the same DDS domain and tag.
struct UnknownComponent {
  std::string address;
  protocol::component::Announcement announcement;
};

// A component process on a node when the node was lost: its pid and label (APPLICATION/COMPONENT,
// as the node lists it).
struct LostProcess {
  long pid = 0;
  std::string label;
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
  std::optional<FileManager> files; // the repository's files, as nodes get them
  ApplicationRegistry applications;
  LaunchTracker launches;
  std::uint64_t incarnation = 0; // this run of the daemon, counted in the store
  process::CpuSampler sampler;   // domain.top's: its last reading of this daemon
  std::atomic<std::uint64_t> launch_counter{0};
  // Held while an uninstall checks for launches of the application and removes it, and while a
  // launch finds its installed application and reserves its name: neither slips between the
  // other's two steps.
  std::mutex installs;
  std::mutex kept_connections; // a runtime connection and its record in the store change together

  NodeDirectory nodes;
  std::mutex unknown_mutex; // guards unknown
  std::map<std::string, UnknownComponent> unknown;
  std::mutex lost_mutex; // guards lost_processes and node_epochs
  std::map<std::string, std::vector<LostProcess>> lost_processes; // by node, until it is back
  std::map<std::string, std::uint64_t> node_epochs;               // by node: one more at each loss
  std::atomic<bool> stopping_node_returns{false};
  // Where a node that is back is asked what it runs: the announcement's thread must not wait.
  std::unique_ptr<control::WorkerPool> node_returns;

  ApplicationFactory factory();
  // Runs a change of `name`'s state under the registry's lock (ApplicationFactory::ApplyChange).
  ApplicationFactory::ApplyChange apply_to(const std::string &name);

  // Installs and applications (domain_manager.cpp).
  CallResult<domain_ops::InstallReply> install(const domain_ops::InstallRequest &request);
  CallResult<domain_ops::Named> uninstall(const domain_ops::Named &request);
  CallResult<domain_ops::InstalledReply> list_installed();
  CallResult<app_ops::CreateReply> create_application(const app_ops::CreateRequest &request);
  CallResult<app_ops::CreateReply> create_installed(const app_ops::CreateRequest &request);
  CallResult<std::shared_ptr<Application>>
  launch(LaunchRequest &request, const std::string &launch_id, std::vector<LaunchStep> &steps);
  CallResult<app_ops::ProgressReply> progress(const app_ops::LaunchId &request);
  CallResult<protocol::file::ReadReply> read_file(const protocol::file::ReadRequest &request);
  CallResult<app_ops::CancelReply> cancel_launch(const app_ops::LaunchId &request);
  CallResult<app_ops::ReleaseReply> release(const app_ops::AppRequest &request);
  CallResult<app_ops::ApplicationView> start_or_stop(const app_ops::AppRequest &request,
                                                     bool start);
  CallResult<app_ops::ConfigureReply> configure(const app_ops::ConfigureRequest &request);
  CallResult<protocol::component::QueryReply> query(const app_ops::QueryRequest &request);
  CallResult<protocol::component::QueryReply>
  query_application(const Application &app, const std::vector<std::string> &ids);
  CallResult<protocol::Empty> configure_at(const std::string &address, control::Json properties);
  CallResult<protocol::component::QueryReply> query_at(const std::string &address,
                                                       std::vector<std::string> ids);
  CallResult<app_ops::ListReply> list_applications();
  CallResult<app_ops::ApplicationView> show_application(const app_ops::AppRequest &request);
  CallResult<app_ops::PlanReply> plan_application(const app_ops::PlanRequest &request);
  CallResult<app_ops::PlanReply> plan_files(const app_ops::PlanFilesRequest &request);
  CallResult<app_ops::PlanReply> plan_profile(const profile::ResolvedApplication &profile,
                                              const std::string &name,
                                              const std::map<std::string, std::string> &assign,
                                              const std::optional<std::string> &strategy);
  CallResult<protocol::Empty> component_exited(const protocol::domain::ComponentExitedReport &r);
  CallResult<protocol::Empty>
  connection_problem(const protocol::domain::ConnectionProblemReport &r);
  // Marks the running components `which` selects as exited.
  void mark_exited(const std::function<bool(const ComponentInstance &)> &which,
                   const std::string &why);
  void serve();
  // Serves `Op` with `handler` (a method of the request, or of nothing); every reply passes
  // as_domain_reply.
  template <control::Operation Op, typename Handler>
  void serve_op(Handler handler);

  // Nodes that announce themselves, are lost and are back (domain_nodes.cpp).
  void node_alive(const control::AnnouncementEvent &event);
  // A node withdrawn (it stopped) or lost (its lease ran out: dead, or cut off).
  void node_gone(const std::string &address, bool withdrawn);
  void end_earlier_run(const std::string &address, const protocol::node::NodeAnnouncement &now);
  void mark_unreachable(const std::string &node, const std::string &why);
  void end_when_back(const std::string &node, long pid, const std::string &label);
  void node_back(const std::string &node, std::uint64_t epoch);
  std::uint64_t node_epoch(const std::string &node);
  std::optional<std::set<long>> processes_on(const std::string &node, std::uint64_t epoch);

  // Devices, connections and channels (domain_connections.cpp).
  void on_announcement(const control::AnnouncementEvent &event);
  void component_announced(const control::AnnouncementEvent &event);
  CallResult<std::string> device_address(const std::string &id);
  CallResult<ResolvedEnd> resolve_end(const PortRef &ref, profile::PortDirection direction);
  CallResult<ResolvedEnd> resolve_component_end(const PortRef &ref,
                                                profile::PortDirection direction);
  CallResult<ResolvedEnd> resolve_device_end(const PortRef &ref, profile::PortDirection direction);
  CallResult<domain_ops::NodesReply> list_nodes();
  CallResult<domain_ops::DevicesReply> list_devices();
  CallResult<domain_ops::TopReply> top();
  CallResult<connection_ops::ChannelsReply> list_channels();
  CallResult<connection_ops::ChannelView> create_channel(const domain_ops::Named &request);
  CallResult<domain_ops::Named> destroy_channel(const domain_ops::Named &request);
  CallResult<connection_ops::ListReply>
  list_connections(const connection_ops::ListRequest &request);
  // The application as app.show shows it: its connections with their live state.
  app_ops::ApplicationView live_view_of(const Application &app);
  CallResult<connection_ops::CreateReply>
  create_connection(const connection_ops::CreateRequest &request);
  CallResult<connection_ops::ConnectionId>
  destroy_connection(const connection_ops::ConnectionId &request);
  CallResult<RuntimeConnection> make_connection(const connection_ops::CreateRequest &request);
  void restore_connections();
  std::vector<app_ops::UnknownComponent> unknown_components();
};

} // namespace rsca::domain
