// Private to the component runtime: one component behind its control endpoint. The host checks
// the component against its profile, serves the component.* operations (docs/architecture.md),
// keeps the announcement up to date with the component's state, and runs the service thread and
// the receive thread.
#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

#include "component/component.hpp"
#include "component/participant_source.hpp"
#include "component/receive_loop.hpp"
#include "control/endpoint.hpp"
#include "dds/participant.hpp"
#include "profile/code_description.hpp"
#include "profile/profile_loader.hpp"
#include "protocol/component_ops.hpp"
#include "protocol/node_ops.hpp"

namespace rsca::component::detail {

using control::CallResult;
using control::Json;

class Host {
public:
  Host(std::unique_ptr<Component> component,
       std::shared_ptr<const profile::ResolvedSoftPkg> softpkg)
      : component_(std::move(component)), softpkg_(std::move(softpkg)) {}
  ~Host() { close(); }
  Host(const Host &) = delete;
  Host &operator=(const Host &) = delete;

  // Checks the bindings against the PRF and the ports against the SCD, then applies the PRF
  // defaults and the execparams (DEBUG_LEVEL sets the log level).
  Expected<void> prepare(const std::vector<std::pair<std::string, std::string>> &execparams);
  // Starts the receive thread, serves the operations at the component's control address and
  // announces it there: on `server` when given (its host's, which serves the address too, or
  // the process's link to its node), else on an endpoint of its own opened with `options` on
  // the participant. Data connections over DDS join the participant `participants` gives.
  // `on_released` runs once the component is released, by component.release or shutdown.
  Expected<void> open(std::shared_ptr<ParticipantSource> participants,
                      std::shared_ptr<control::Server> server, std::function<void()> on_released,
                      control::EndpointOptions options = {});
  // Stops (when started) and releases the component and drops its connections. Idempotent.
  void shutdown(std::string_view why);
  // Initializes, configures with `properties` and starts the component: what the domain would
  // ask, for a component its own process brings up (a device in its node).
  Expected<void> bring_up(const Json &properties);
  // What the component's code declares (ports, bound properties), as `--rsca-describe` writes it.
  static profile::CodeDescription describe(const Component &component);
  // The component's ports, as a device announces them.
  std::vector<protocol::node::DevicePort> ports() const;
  // Withdraws the announcement, closes the endpoint (waiting for running operations), stops the
  // threads and destroys the component. Idempotent.
  void close();

private:
  template <typename Op>
  using Operation = CallResult<typename Op::Reply> (Host::*)(const typename Op::Request &,
                                                             const control::RequestContext &);

  Expected<void> check_ports() const;
  void serve_operations();
  template <typename Op>
  void serve(Operation<Op> op);
  protocol::component::Announcement announcement() const;
  void set_state(State state);
  PortBase *find_port(const std::string &name) const;
  ResourceUsesPort *find_resource_port(const std::string &name) const;
  CallResult<protocol::Empty> connect_resource_port(ResourceUsesPort &port,
                                                    const protocol::component::ConnectRequest &r);
  void poll_ports();
  void watch_connections();
  std::string domain_address() const;
  // Tells the domain of connection problems, at most once a second (only the receive thread).
  void report_problems(std::vector<ConnectionProblem> problems);
  void configure_thread(std::thread &thread, std::string_view prefix);
  void start_service();
  void stop_service();
  void service_loop();
  void stop_component();

  // The component.* operations (component_operations.cpp).
  using Empty = protocol::Empty;
  using Context = control::RequestContext;
  CallResult<Empty> op_initialize(const Empty &, const Context &);
  CallResult<Empty> op_configure(const protocol::component::ConfigureRequest &r, const Context &);
  CallResult<protocol::component::QueryReply> op_query(const protocol::component::QueryRequest &r,
                                                       const Context &);
  CallResult<protocol::component::ConnectReply>
  op_connect(const protocol::component::ConnectRequest &r, const Context &);
  CallResult<protocol::component::ConnectReply>
  connect_tcp(PortBase &port, const protocol::component::ConnectRequest &r, const dds_qos_t *qos);
  CallResult<Empty> op_disconnect(const protocol::component::DisconnectRequest &r, const Context &);
  CallResult<Empty> op_start(const Empty &, const Context &);
  CallResult<Empty> op_stop(const Empty &, const Context &);
  CallResult<protocol::component::StatusReply> op_status(const Empty &, const Context &);
  CallResult<protocol::component::AwaitMatchedReply>
  op_await_matched(const protocol::component::AwaitMatchedRequest &r, const Context &context);
  CallResult<Empty> op_release(const Empty &, const Context &);

  Component &c() const { return *component_; }
  spdlog::logger &log() const { return component_->log(); }

  std::unique_ptr<Component> component_;
  std::shared_ptr<const profile::ResolvedSoftPkg> softpkg_;
  std::shared_ptr<ParticipantSource> participants_;
  std::unique_ptr<ReceiveLoop> loop_;
  std::shared_ptr<control::Server> endpoint_;
  std::string address_; // the component's control address
  std::function<void()> on_released_;

  std::mutex lifecycle_; // one lifecycle operation at a time
  std::map<std::pair<std::string, std::string>, std::uint32_t> unreported_problems_;
  std::chrono::steady_clock::time_point last_problem_report_{};
  static constexpr std::chrono::milliseconds kProblemCheck{100};
  std::chrono::steady_clock::time_point last_problem_check_{}; // only the receive thread
  bool delivered_at_last_poll_ = false;                        // only the receive thread

  std::mutex service_mutex_;
  std::condition_variable service_wake_;
  bool service_stopping_ = false;
  std::thread service_thread_;
};

} // namespace rsca::component::detail
