// A component run inside the calling process rather than as a process of its own: a device with
// ports inside its node daemon. It is served exactly as a component process is (the component.*
// operations at its control address, its announcement), so the domain connects, configures and
// queries it the same way.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "component/component.hpp"
#include "component/participant_source.hpp"
#include "component/runtime.hpp"
#include "control/endpoint.hpp"
#include "dds/participant.hpp"
#include "profile/profile_loader.hpp"
#include "protocol/node_ops.hpp"

namespace rsca::component {

namespace detail {
class Host;
}

class InProcessComponent {
public:
  // Constructs the component, checks it against its profile (PRF and SCD), applies `execparams`
  // and serves it at `context.control_address`: through `server` when given (a component
  // host's endpoint, with that address among its aliases, or its link to its node), else through
  // an endpoint of its own on the participant. Its DDS data connections join the participant
  // `participants` gives. `on_released` runs once the domain has released it (component.release).
  static Expected<std::unique_ptr<InProcessComponent>>
  open(const Factory &factory, Context context,
       std::shared_ptr<const profile::ResolvedSoftPkg> softpkg,
       std::shared_ptr<ParticipantSource> participants,
       const std::vector<std::pair<std::string, std::string>> &execparams = {},
       std::function<void()> on_released = {}, std::shared_ptr<control::Server> server = nullptr);
  ~InProcessComponent(); // stops and releases the component, then withdraws it
  InProcessComponent(const InProcessComponent &) = delete;
  InProcessComponent &operator=(const InProcessComponent &) = delete;

  // Initializes, configures with `properties` (by id) and starts it, as its owner decides (a
  // node brings its devices up itself; no domain does).
  Expected<void> bring_up(const control::Json &properties);
  const std::string &address() const { return address_; }
  // Its ports as announced: [{"name", "direction", "repid"}].
  std::vector<protocol::node::DevicePort> ports() const;

private:
  explicit InProcessComponent(std::unique_ptr<detail::Host> host, std::string address);
  std::unique_ptr<detail::Host> host_;
  std::string address_;
};

// A logger for an in-process component: named after it, writing where the process's default
// logger writes.
std::shared_ptr<spdlog::logger> in_process_logger(const std::string &name);

} // namespace rsca::component
