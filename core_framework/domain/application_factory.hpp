// ApplicationFactory: turns an installed application into running components, in SCA's order —
// check the wiring, allocate devices, execute, wait for registration, initialize, configure,
// connect, start — each step for all components at once. A failure at any step rolls back all
// that was done (processes, allocations, connections) and says which step failed and why.
#pragma once

#include <atomic>

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "allocator/resource_allocator.hpp"
#include "control/caller.hpp"
#include "domain/application.hpp"
#include "domain/component_registry.hpp"
#include "domain/event_channel_manager.hpp"
#include "domain/file_manager.hpp"
#include "protocol/addresses.hpp"
#include "protocol/node_ops.hpp"

namespace rsca::domain {

struct LaunchStep {
  std::string step;   // "check", "allocate", "execute", "register", ...
  std::string detail; // what was done
  double milliseconds = 0;
};
using ProgressSink = std::function<void(const LaunchStep &)>;

struct LaunchRequest {
  std::string name;      // the instance name
  std::string installed; // the installed application
  std::shared_ptr<const profile::ResolvedApplication> profile;
  std::map<std::string, std::string> assignments; // instance id → device id
  std::optional<allocator::Strategy> strategy;    // the domain's when not given
  bool start = true;
  std::string id; // the caller's id of the launch: its progress, and the files delivered for it
  // Set while the launch runs to have it stop and roll back (ComponentRegistry::interrupt() ends
  // a registration wait at once); checked before each step.
  std::shared_ptr<const std::atomic<bool>> cancelled;
};

// A device's data ports as its node announced them.
struct DevicePorts {
  std::string address;
  std::vector<protocol::node::DevicePort> ports;
};

// A launch's identity: the domain daemon's incarnation (counted in its store, one more at each
// start) and the launch's number within it (protocol/addresses.hpp).
using protocol::LaunchIdentity;

// What the factory uses of the domain.
struct DomainServices {
  std::string domain_name;
  control::Caller *endpoint = nullptr; // the domain's Endpoint; a fake in unit tests
  allocator::ResourceAllocator *allocator = nullptr;
  ComponentRegistry *components = nullptr;
  EventChannelManager *channels = nullptr;
  std::function<std::optional<std::string>(const std::string &node)> node_address;
  // Whether a node relays the control of the processes it starts (null: none does).
  std::function<bool(const std::string &node)> node_relays;
  std::function<std::optional<DevicePorts>(const std::string &device)> device_ports;
  // An identity unique to each launch in this domain, also across restarts of the domain daemon:
  // component addresses and topics carry it, so an application re-launched under the same name
  // never meets its predecessor's leftovers, not even those of a domain daemon that was killed.
  std::function<LaunchIdentity()> next_launch;
  // Makes the package each process gets (domain/file_manager.hpp). Null (a unit test's): the
  // processes get no package, and the paths of the domain's files.
  FileManager *files = nullptr;
  // Has a process that could not be ended (its node is lost) ended when its node is back: a
  // rolled-back launch or a release must not leave it running for nobody. Null (a unit test's):
  // such a process is left to its node.
  std::function<void(const std::string &node, long pid, const std::string &label)> end_when_back;
  // Told of each launch that failed after starting processes (null: nobody), so that their
  // logs stay reachable (app.failed).
  std::function<void(protocol::application::FailedLaunch)> launch_failed;
  std::chrono::milliseconds call_timeout{5000};
  std::chrono::milliseconds registration_timeout{10000};
  allocator::Strategy strategy = allocator::Strategy::Pack;
};

class ApplicationFactory {
public:
  explicit ApplicationFactory(DomainServices services) : services_(std::move(services)) {}

  control::CallResult<std::shared_ptr<Application>> create(const LaunchRequest &request,
                                                           const ProgressSink &progress);
  // Start and stop work from a copy of the application (its components that exited are left
  // alone) and change its state only through `apply`, which runs a change under its owner's
  // lock (ApplicationRegistry::update).
  using ApplyChange = std::function<void(const std::function<void(Application &)> &change)>;
  control::CallResult<void> start(const Application &app, const ApplyChange &apply);
  control::CallResult<void> stop(const Application &app, const ApplyChange &apply);
  // What releasing an application's processes left: components that did not confirm their
  // release (their node terminated them), and processes left to end when their node is back.
  struct ProcessesReleased {
    std::vector<std::string> unconfirmed; // not those whose node is lost
    std::size_t terminated = 0;
    std::size_t deferred = 0;
    std::vector<protocol::application::LostComponent> lost; // the components of those deferred
  };
  // Stops, releases and terminates every component, and frees the allocation. Best effort: a
  // component that does not confirm its release is terminated by its node all the same, and
  // named in the result; one whose node is lost is ended when the node is back.
  control::CallResult<ProcessesReleased> release(Application &app);

private:
  class Launch;
  // The undoable parts of a release, which a failed launch also runs (its saga): the devices'
  // ends of the application's connections (how many), and its processes.
  std::size_t disconnect_devices(const Application &app);
  control::CallResult<ProcessesReleased> release_processes(Application &app);
  DomainServices services_;
};

} // namespace rsca::domain
