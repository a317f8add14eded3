// A uses port of a CF control interface (IDL:CF/Resource:1.0, or one it inherits: PropertySet,
// LifeCycle, ...), connected by a SAD connection to another component's supported interface
// (`componentsupportedinterface`). Over DDS a component's own interface is its control endpoint,
// so a connection holds the connected component's control address, and the port's calls go
// there through the control plane: what a REDHAWK uses port of CF::Resource does with the object
// references it holds. Each call waits for the reply, up to its timeout. The runtime holds the
// component's property lock around service(), port callbacks and lifecycle hooks, and a component
// serves configure and query under that lock: so a component may call others from there, but two
// components must not call each other (each would wait for the other's lock until the timeout),
// and a component cannot call itself (the SAD check refuses that).
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "control/server.hpp"

namespace rsca::component {

class ResourceUsesPort {
public:
  // Below the domain's call timeout (5 s): a component whose call is stuck still answers the
  // domain's release in time.
  static constexpr std::chrono::milliseconds kDefaultTimeout{2000};

  explicit ResourceUsesPort(std::string name) : name_(std::move(name)) {}
  ResourceUsesPort(const ResourceUsesPort &) = delete;
  ResourceUsesPort &operator=(const ResourceUsesPort &) = delete;

  const std::string &name() const { return name_; }
  struct Target {
    std::string address;     // the connected component's control address
    std::uint64_t calls = 0; // made through this connection
  };
  // The connected components, by connection id.
  std::map<std::string, Target> targets() const;

  // Each call goes to every connected component in turn and stops at the first failure, which
  // names the component; a connection removed meanwhile is skipped. Without connections they do
  // nothing.
  control::CallResult<void> configure(const nlohmann::json &properties,
                                      std::chrono::milliseconds timeout = kDefaultTimeout);
  // One {"id": value} object per connected component, by connection id.
  control::CallResult<std::map<std::string, nlohmann::json>>
  query(const std::vector<std::string> &ids, std::chrono::milliseconds timeout = kDefaultTimeout);
  control::CallResult<void> start(std::chrono::milliseconds timeout = kDefaultTimeout);
  control::CallResult<void> stop(std::chrono::milliseconds timeout = kDefaultTimeout);

  // For the runtime: `connect` replaces a connection of the same id.
  void connect(const std::string &connection, const std::string &target,
               std::weak_ptr<control::Server> endpoint);
  bool disconnect(const std::string &connection);
  void disconnect_all();

private:
  // Operation `Op` (protocol/component_ops.hpp) to every target; the replies by connection id.
  template <typename Op>
  control::CallResult<std::map<std::string, typename Op::Reply>>
  call_each(const typename Op::Request &request, std::chrono::milliseconds timeout);

  std::string name_;
  mutable std::mutex mutex_;
  std::map<std::string, Target> targets_; // by connection id
  std::weak_ptr<control::Server> endpoint_;
};

} // namespace rsca::component
