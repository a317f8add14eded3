// Private to the ApplicationFactory: one launch, step by step (launch.cpp; its connect step in
// launch_wiring.cpp). Each step that does something registers its undo in the launch's saga; a
// failure runs them in reverse and reports what was undone.
#pragma once

#include <memory>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "domain/application_factory.hpp"
#include "domain/factory_calls.hpp"
#include "domain/saga.hpp"
#include "domain/wiring.hpp"
#include "protocol/exec_params.hpp"

namespace rsca::domain {

class ApplicationFactory::Launch {
  template <typename T>
  using CallResult = control::CallResult<T>;
  using Call = detail::Call;

public:
  Launch(const DomainServices &services, const LaunchRequest &request, const ProgressSink &progress)
      : s_(services), request_(request), progress_(progress), app_(std::make_shared<Application>()),
        launch_(s_.next_launch ? s_.next_launch() : LaunchIdentity{}) {
    app_->name = request.name;
    app_->installed = request.installed;
    app_->profile = request.profile;
    app_->sad = request.profile->sad_path.string();
    for (const auto &placement : request.profile->sad->placements)
      for (const auto &ci : placement.instantiations)
        instances_[ci.id] = {&ci, &placement, nullptr, kNone};
  }

  CallResult<std::shared_ptr<Application>> run();

private:
  // What the profile alone makes unlaunchable (profile::launch_refusals: missing files, wiring
  // findings, connections rsca cannot make yet) and event-channel members that could never match
  // the channel's others stop a launch before anything runs.
  CallResult<void> check();

  // This application's publishers and subscribers of event channels, by channel name.
  std::vector<std::pair<std::string, ChannelMember>> channel_members() const;

  static std::string connection_id(const profile::Connection &c, std::size_t index);

  static const std::string &channel_name(const profile::Connection &c);

  CallResult<void> allocate();

  // One process per Executable component, and one component host per device for the
  // application's SharedLibrary components on it; all started at once.
  CallResult<void> execute();
  void route(ComponentInstance &c);

  CallResult<void> await_registration();

  CallResult<void> initialize();

  CallResult<void> configure();

  CallResult<void> connect();

  // A SAD connection with its ends resolved.
  CallResult<ConnectionInstance> connection_of(const profile::Connection &c, std::size_t index);

  Wire wire_of(const ConnectionInstance &ci) const;

  // One end of a SAD connection: a port of one of this application's components, or of the
  // device that loaded or is used by one of them (checked against what its node announced);
  // nothing for an event channel.
  CallResult<ConnectionEnd> resolve_end(ConnectionInstance &ci,
                                        const profile::EndpointTarget &target,
                                        const std::string &port, profile::PortDirection direction);

  tl::expected<std::string, std::string> device_of(const profile::EndpointTarget &target) const;

  CallResult<ConnectionEnd> device_end(ConnectionInstance &ci, const std::string &device,
                                       const std::string &port, profile::PortDirection direction);

  // This application's subscribers (or publishers) on a channel's topic.
  std::string relaying_node_of(const ConnectionInstance &ci, const ConnectionEnd &end) const;
  int channel_peers(const ConnectionInstance &self, const ConnectionEnd &end,
                    bool subscribers) const;

  CallResult<void> start();

  // --- helpers ---

  template <control::Operation Op, typename Request>
  CallResult<void> call_each(Request request);

  std::string repid_of(const profile::Connection &c) const;

  // The exec parameters of a component (protocol/exec_params.hpp); a hosted one's name the
  // library its host loads, as the SPD names it (the host resolves it, as a GPP resolves an
  // entry point).
  protocol::ExecParams exec_params(const ComponentInstance &c) const;
  // Whether a SAD connection of `c` goes on DDS from its own process (launch_wiring.cpp).
  bool joins_dds(const ComponentInstance &c) const;

  static bool is_hosted(const ComponentInstance &c) { return !c.host.empty(); }

  protocol::node::ExecuteRequest execute_request(const ComponentInstance &c) const;
  // The instance's affinity (SAD componentinstantiation/affinity), for the node to apply.
  std::optional<protocol::node::AffinityDirective> affinity_of(const ComponentInstance &c) const;
  // Gives each request the package of the components it starts (started_by, by request); the
  // bytes they hold.
  CallResult<std::uint64_t>
  add_packages(std::vector<protocol::node::ExecuteRequest> &requests,
               const std::vector<std::vector<std::size_t>> &started_by) const;
  // How a process names a file of the domain's: its path in its package.
  std::string in_package(const std::filesystem::path &file) const;

  // A component host's process at its own address; its components' exec parameters follow.
  protocol::node::ExecuteRequest host_request(const ComponentInstance &first) const;
  // The name of the process a component runs in, and of its log on its node: its own id, or its
  // component host's.
  std::string process_name(const ComponentInstance &c) const;

  // The component's execparam-only properties, as its SAD instantiation sets them.
  std::vector<std::pair<std::string, std::string>> execparams(const ComponentInstance &c) const;

  const allocator::Placement *placement_of(const std::string &instance) const;

  // The SAD's instantiation of that id, and the placement holding it; nullptr when none.
  const profile::ComponentInstantiation *
  instantiation_of(const std::string &instance,
                   const profile::ComponentPlacement **placement = nullptr) const;

  ComponentInstance *component_of(const std::string &instance) const;

  void build_components();

  std::size_t count_instances() const;

  std::vector<std::string> nodes_used() const;

  CallResult<std::shared_ptr<Application>> fail(const char *step, const control::CallError &error);
  // The failed launch as app.failed tells it; nullopt when it had started no process.
  std::optional<protocol::application::FailedLaunch> failed_launch(const char *step) const;

  // Per instance id: the SAD's instantiation and placement, the allocator's placement and the
  // component (an index into app_->components), so that per-component and per-connection
  // look-ups keep a launch linear in its size.
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  struct Instance {
    const profile::ComponentInstantiation *instantiation = nullptr;
    const profile::ComponentPlacement *placement = nullptr;
    const allocator::Placement *planned = nullptr;
    std::size_t component = kNone;
  };
  std::unordered_map<std::string, Instance> instances_;

  const DomainServices &s_;
  const LaunchRequest &request_;
  const ProgressSink &progress_;
  std::shared_ptr<Application> app_;
  Saga saga_;             // the undo of every step that did something
  LaunchIdentity launch_; // addresses and topics carry it
  std::string detail_;
};

} // namespace rsca::domain
