// What a component author derives from. The constructor declares the component's properties
// (bound to member variables) and ports; the runtime (component/runtime.hpp) checks them against
// the component's PRF and SCD, then drives the lifecycle the domain asks for:
//
//   class Counter : public rsca::component::Component {
//   public:
//     explicit Counter(const Context &context) : Component(context) {
//       property("limit", limit_);
//       provides_port<rsca::port::Samples>("in", [this](const auto &s) { ++count_; });
//     }
//   private:
//     Result start() override { count_ = 0; return {}; }
//     std::uint32_t limit_ = 10;
//     std::atomic<std::uint64_t> count_{0};
//   };
//   int main(int argc, char **argv) { return rsca::component::run<Counter>(argc, argv); }
//
// Threads. Control operations arrive on the endpoint's worker threads, one at a time per
// component. The runtime holds the property lock (lock_properties(), recursive) while it runs
// the lifecycle hooks, service() and change callbacks and while it reads or writes bound
// variables; provides-port callbacks run on the receive thread without it: read properties
// there under lock_properties() or bind std::atomic variables.
#pragma once

#include <atomic>
#include <chrono>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include <spdlog/logger.h>

#include "component/port_types.hpp"
#include "component/ports.hpp"
#include "component/properties.hpp"
#include "component/resource_port.hpp"
#include "control/endpoint.hpp"
#include "protocol/exec_params.hpp"

namespace rsca::component {

using Clock = std::chrono::steady_clock;
// What a hook returns: {} or why it failed (the control call fails with that status and text).
using Result = control::CallResult<void>;
inline tl::unexpected<control::CallError> failure(std::string message) {
  return control::call_error(control::Status::Failed, std::move(message));
}

enum class State : std::uint8_t { Loaded, Initialized, Started, Stopped, Released };
std::string_view to_string(State state);

// Who the component is: from its exec parameters.
// What timing admission decided for a periodic component (RSCA): the CPU it runs on (the
// runtime pins the process there), its priority, its period, its execution budget per period
// and its deadline. The component paces itself by it.
using Schedule = protocol::Schedule;

struct Context {
  std::string identifier;                 // COMPONENT_IDENTIFIER
  std::string name;                       // NAME_BINDING (the identifier when not given)
  std::string application;                // APPLICATION
  std::string domain;                     // DOMAIN_NAME
  std::filesystem::path profile;          // PROFILE_NAME: the SPD
  std::string control_address;            // CONTROL_ADDRESS
  std::shared_ptr<spdlog::logger> logger; // named after the instance
  std::optional<Schedule> schedule;       // periodic components only
  // A connection of it goes on DDS from its own process (RSCA_DDS): the process joins DDS as
  // it starts. Else it joins at its first such connection, if any comes.
  bool joins_dds = false;
};

namespace detail {
class Host;
}

class Component {
public:
  explicit Component(Context context);
  virtual ~Component();
  Component(const Component &) = delete;
  Component &operator=(const Component &) = delete;

  const Context &context() const { return context_; }
  const std::string &identifier() const { return context_.identifier; }
  const std::string &name() const { return context_.name; }
  spdlog::logger &log() const { return *context_.logger; }
  State state() const { return state_.load(); }
  std::unique_lock<std::recursive_mutex> lock_properties() const {
    return std::unique_lock(properties_mutex_);
  }

protected:
  // ---- Declarations: call from the constructor only.

  template <typename T>
  void property(std::string id, T &variable,
                std::type_identity_t<ChangeCallback<T>> on_change = {}) {
    properties_.bind(std::move(id),
                     std::make_unique<detail::ScalarBinding<T>>(variable, std::move(on_change)));
  }
  template <typename T>
  void property(std::string id, std::atomic<T> &variable,
                std::type_identity_t<ChangeCallback<T>> on_change = {}) {
    properties_.bind(std::move(id),
                     std::make_unique<detail::AtomicBinding<T>>(variable, std::move(on_change)));
  }
  template <typename T>
  void property(std::string id, std::vector<T> &variable,
                std::type_identity_t<ChangeCallback<std::vector<T>>> on_change = {}) {
    properties_.bind(std::move(id),
                     std::make_unique<detail::SequenceBinding<T>>(variable, std::move(on_change)));
  }
  // A struct property: every PRF member needs a field, e.g.
  //   struct_property("stream", stream_, {{"stream_id", &Stream::id}, {"rate", &Stream::rate}});
  template <typename S>
  void struct_property(std::string id, S &variable, std::vector<Field<S>> fields,
                       std::type_identity_t<ChangeCallback<S>> on_change = {}) {
    properties_.bind(std::move(id), std::make_unique<detail::StructBinding<S>>(
                                        variable, std::move(fields), std::move(on_change)));
  }
  template <typename S>
  void
  struct_sequence_property(std::string id, std::vector<S> &variable, std::vector<Field<S>> fields,
                           std::type_identity_t<ChangeCallback<std::vector<S>>> on_change = {}) {
    properties_.bind(std::move(id), std::make_unique<detail::StructSequenceBinding<S>>(
                                        variable, std::move(fields), std::move(on_change)));
  }

  // A uses port of the SCD; the port lives as long as the component.
  template <typename T>
  UsesPort<T> &uses_port(std::string name) {
    return add_port(std::make_unique<UsesPort<T>>(std::move(name)));
  }
  // A provides port of the SCD; `on_sample` runs on the receive thread while started. With
  // Delivery::Listener (component/ports.hpp) the author promises `on_sample` is short and never
  // blocks, and it then runs on DDS's receive thread when it can, a thread wake-up sooner.
  template <typename T>
  ProvidesPort<T> &provides_port(std::string name, typename ProvidesPort<T>::Callback on_sample,
                                 Delivery delivery = Delivery::ReceiveThread) {
    return add_port(
        std::make_unique<ProvidesPort<T>>(std::move(name), std::move(on_sample), delivery));
  }

  // A uses port of a CF control interface (its SCD repid IDL:CF/Resource:1.0 or one it
  // inherits), for connections to other components' supported interface; lives as long as the
  // component.
  ResourceUsesPort &resource_port(std::string name) {
    resource_ports_.push_back(std::make_unique<ResourceUsesPort>(std::move(name)));
    return *resource_ports_.back();
  }

  // ---- Hooks, run by the runtime with the property lock held.

  // component.initialize: once, after the PRF defaults and execparams are applied.
  virtual Result initialize() { return {}; }
  // component.start: the service thread starts after it succeeds.
  virtual Result start() { return {}; }
  // component.stop: the service thread has stopped and port callbacks are off.
  virtual Result stop() { return {}; }
  // component.release (or SIGTERM/SIGINT): after stop; the ports' connections go afterwards.
  virtual Result release() { return {}; }

  // Called on the service thread while started: returns the time from this call's scheduled
  // time to the next one (a fixed rate: 10ms gives 100 calls per second, catching up after a
  // late call by at most one period), or nullopt to stop being called until the next start.
  virtual std::optional<Clock::duration> service() { return std::nullopt; }

private:
  friend class detail::Host;

  template <typename P>
  P &add_port(std::unique_ptr<P> port) {
    P &ref = *port;
    ports_.push_back(std::move(port));
    return ref;
  }

  Context context_;
  mutable std::recursive_mutex properties_mutex_;
  PropertySet properties_;
  std::vector<std::unique_ptr<PortBase>> ports_;
  std::vector<std::unique_ptr<ResourceUsesPort>> resource_ports_;
  std::atomic<State> state_{State::Loaded};
};

} // namespace rsca::component
