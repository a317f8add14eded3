// The component.* operations a Host serves (protocol/component_ops.hpp): each takes its typed
// request, decoded and checked for shape by the endpoint (control/operation.hpp), checks what
// only the component can (its ports, its state), and acts under the lifecycle lock.
#include <algorithm>
#include <thread>

#include <fmt/format.h>

#include "common/content_filter.hpp"
#include "component/host.hpp"
#include "component/tcp_stream.hpp"
#include "control/operation.hpp"
#include "dds/port_qos.hpp"

namespace rsca::component::detail {

using control::Status;
namespace op = protocol::component;

namespace {

// Names that must not be empty: a connection and a port are always named.
CallResult<void>
check_named(std::initializer_list<std::pair<const char *, const std::string *>> names) {
  for (const auto &[key, value] : names)
    if (value->empty())
      return control::call_error(Status::BadRequest,
                                 fmt::format("the request needs \"{}\", a non-empty string", key));
  return {};
}

tl::unexpected<control::CallError> released() {
  return control::call_error(Status::Unavailable, "the component is released");
}

op::AppliedQos applied_qos_message(const AppliedQos &q) {
  return {std::string(profile::to_string(q.reliability)),
          std::string(profile::to_string(q.history)),
          q.depth,
          std::string(profile::to_string(q.durability)),
          std::string(profile::to_string(q.ownership)),
          q.deadline_ns,
          std::string(profile::to_string(q.liveliness)),
          q.lease_ns};
}

} // namespace

// Runs `op` for its operation at the component's address: exceptions become errors.
template <typename Op>
void Host::serve(Operation<Op> op) {
  control::serve<Op>(
      *endpoint_, address_,
      [this, op](const typename Op::Request &request,
                 const control::RequestContext &context) -> CallResult<typename Op::Reply> {
        log().debug("{} from {}", context.operation, context.sender);
        try {
          return (this->*op)(request, context);
        } catch (const std::exception &e) {
          return control::call_error(Status::Failed, e.what());
        }
      });
}

void Host::serve_operations() {
  serve<op::Initialize>(&Host::op_initialize);
  serve<op::Configure>(&Host::op_configure);
  serve<op::Query>(&Host::op_query);
  serve<op::Connect>(&Host::op_connect);
  serve<op::Disconnect>(&Host::op_disconnect);
  serve<op::Start>(&Host::op_start);
  serve<op::Stop>(&Host::op_stop);
  serve<op::Status>(&Host::op_status);
  serve<op::AwaitMatched>(&Host::op_await_matched);
  serve<op::Release>(&Host::op_release);
}

CallResult<protocol::Empty> Host::op_initialize(const Empty &, const Context &) {
  std::lock_guard lock(lifecycle_);
  if (c().state() == State::Released)
    return released();
  if (c().state() != State::Loaded)
    return Empty{}; // already initialized
  {
    auto properties = c().lock_properties();
    if (auto ok = c().initialize(); !ok)
      return tl::unexpected(ok.error());
  }
  set_state(State::Initialized);
  return Empty{};
}

CallResult<protocol::Empty> Host::op_configure(const op::ConfigureRequest &r, const Context &) {
  std::lock_guard lock(lifecycle_);
  if (c().state() == State::Released)
    return released();
  auto properties = c().lock_properties();
  auto notifications = c().properties_.configure(r.properties);
  if (!notifications)
    return tl::unexpected(notifications.error());
  for (const auto &notify : *notifications) {
    try {
      notify();
    } catch (const std::exception &e) {
      log().error("a property change callback failed: {}", e.what());
    }
  }
  log().info("configured {}", r.properties.dump());
  return Empty{};
}

CallResult<op::QueryReply> Host::op_query(const op::QueryRequest &r, const Context &) {
  auto properties = c().lock_properties();
  auto values = c().properties_.query(r.ids);
  if (!values)
    return tl::unexpected(values.error());
  return op::QueryReply{std::move(*values)};
}

// A connection of a uses port of a CF control interface to another component's supported
// interface: the port keeps that component's control address ("target").
CallResult<protocol::Empty> Host::connect_resource_port(ResourceUsesPort &port,
                                                        const op::ConnectRequest &r) {
  const std::string target = r.target.value_or("");
  if (auto ok = check_named({{"target", &target}}); !ok)
    return tl::unexpected(ok.error());
  if (r.direction != "uses")
    return control::call_error(Status::BadRequest,
                               fmt::format("port \"{}\" is a uses port", port.name()));
  std::lock_guard lock(lifecycle_);
  if (c().state() == State::Released)
    return released();
  if (r.via && !r.via->empty())
    endpoint_->route(target, *r.via);
  port.connect(r.connection, target, endpoint_);
  log().info("port {}: connection {} to the component at {}", port.name(), r.connection, target);
  return Empty{};
}

CallResult<op::ConnectReply> Host::op_connect(const op::ConnectRequest &r, const Context &) {
  if (auto ok = check_named({{"connection", &r.connection}, {"port", &r.port}}); !ok)
    return tl::unexpected(ok.error());
  if (auto *resource = find_resource_port(r.port)) {
    if (auto ok = connect_resource_port(*resource, r); !ok)
      return tl::unexpected(ok.error());
    return op::ConnectReply{};
  }
  const std::string topic = r.topic.value_or("");
  if (auto ok = check_named({{"topic", &topic}, {"repid", &r.repid}}); !ok)
    return tl::unexpected(ok.error());
  PortBase *port = find_port(r.port);
  if (port == nullptr)
    return control::call_error(Status::NotFound, fmt::format("no port \"{}\"", r.port));
  if (r.direction != profile::to_string(port->direction()))
    return control::call_error(Status::BadRequest,
                               fmt::format("port \"{}\" is a {} port, not {}", r.port,
                                           profile::to_string(port->direction()), r.direction));
  if (port::port_type_for_repid(r.repid) != port->type())
    return control::call_error(Status::BadRequest,
                               fmt::format("port \"{}\" carries {}, which {} does not", r.port,
                                           port::to_string(port->type()), r.repid));
  auto qos = dds::qos_from_json(r.qos.value_or(Json::object()));
  if (!qos)
    return control::call_error(Status::BadRequest, qos.error());
  const std::string filter_text = r.filter.value_or("");
  std::optional<ContentFilter> filter;
  if (!filter_text.empty()) {
    if (port->direction() != profile::PortDirection::Provides)
      return control::call_error(Status::BadRequest,
                                 "only a provides port filters what it receives");
    auto parsed = ContentFilter::parse(filter_text);
    if (!parsed)
      return control::call_error(Status::BadRequest,
                                 fmt::format("filter \"{}\": {}", filter_text, parsed.error()));
    filter = std::move(*parsed);
  }
  std::lock_guard lock(lifecycle_);
  if (c().state() == State::Released)
    return released();
  const bool local = r.local.value_or(false); // the other end is in this process
  if (const auto typed = dds::connection_qos_from_json(r.qos.value_or(Json::object()));
      !local && typed && typed->transport == profile::Transport::Tcp) {
    if (filter)
      return control::call_error(Status::BadRequest,
                                 "a TCP stream carries no content filter (an event channel's)");
    return connect_tcp(*port, r, qos->get());
  }
  if (r.shared_memory.value_or(false) && !r.ring)
    return control::call_error(Status::BadRequest,
                               "a same-host connection needs the ring its node makes; was the "
                               "request relayed by the component's node?");
  std::optional<RingRef> ring;
  if (r.ring && !local)
    ring = RingRef{r.ring->offset, r.ring->slot, r.relay.value_or(false)};
  // In-host and same-host connections need no DDS: the process joins DDS at its first
  // connection that does.
  std::shared_ptr<dds::Participant> participant;
  if (!local && !ring) {
    auto joined = participants_->get();
    if (!joined)
      return control::call_error(Status::Failed, joined.error().to_string());
    participant = std::move(*joined);
  }
  if (auto ok = port->connect(participant ? participant->get() : 0, loop_.get(), r.connection,
                              topic, qos->get(), std::move(filter), local, ring);
      !ok)
    return control::call_error(Status::Failed, ok.error());
  watch_connections();
  log().info("port {}: connection {} on {}topic \"{}\"{}", r.port, r.connection,
             local ? "in-host " : (ring ? (ring->relayed ? "relayed " : "same-host ") : ""), topic,
             filter_text.empty() ? "" : fmt::format(" with filter \"{}\"", filter_text));
  return op::ConnectReply{};
}

// transport="tcp": the reader listens and answers where; the writer connects there. Called with
// the lifecycle lock held.
CallResult<op::ConnectReply> Host::connect_tcp(PortBase &port, const op::ConnectRequest &r,
                                               const dds_qos_t *qos) {
  // How long a writer's connect may take: the reader listens already (it was connected first).
  constexpr std::chrono::milliseconds kConnectTimeout{2000};
  const std::string token = r.tcp_token.value_or("");
  if (!detail::valid_token(token))
    return control::call_error(Status::BadRequest,
                               "a TCP connection needs tcp_token, 8 to 64 hex digits");
  const bool uses = port.direction() == profile::PortDirection::Uses;
  const std::string peer = r.tcp_peer.value_or("");
  if (uses && (peer.empty() || peer.size() > 64))
    return control::call_error(
        Status::BadRequest, "a TCP connection's writer needs tcp_peer, its reader's address:port");
  auto endpoint = port.connect_tcp(loop_.get(), r.connection, qos, peer, token, kConnectTimeout);
  if (!endpoint)
    return control::call_error(Status::Failed, endpoint.error().to_string());
  watch_connections();
  log().info("port {}: connection {} on a TCP stream {} {}", r.port, r.connection,
             uses ? "to" : "listening at", uses ? peer : *endpoint);
  op::ConnectReply reply;
  if (!uses)
    reply.tcp_endpoint = *endpoint;
  return reply;
}

CallResult<protocol::Empty> Host::op_disconnect(const op::DisconnectRequest &r, const Context &) {
  if (auto ok = check_named({{"connection", &r.connection}, {"port", &r.port}}); !ok)
    return tl::unexpected(ok.error());
  auto no_connection = [&r] {
    return control::call_error(Status::NotFound, fmt::format("port \"{}\" has no connection \"{}\"",
                                                             r.port, r.connection));
  };
  if (auto *resource = find_resource_port(r.port)) {
    if (!resource->disconnect(r.connection))
      return no_connection();
    log().info("port {}: connection {} removed", r.port, r.connection);
    return Empty{};
  }
  PortBase *port = find_port(r.port);
  if (port == nullptr)
    return control::call_error(Status::NotFound, fmt::format("no port \"{}\"", r.port));
  std::lock_guard lock(lifecycle_);
  if (!port->disconnect(r.connection))
    return no_connection();
  watch_connections();
  log().info("port {}: connection {} removed", r.port, r.connection);
  return Empty{};
}

CallResult<protocol::Empty> Host::op_start(const Empty &, const Context &) {
  std::lock_guard lock(lifecycle_);
  switch (c().state()) {
  case State::Released:
    return released();
  case State::Loaded:
    return control::call_error(Status::Rejected, "the component is not initialized");
  case State::Started:
    return Empty{};
  default:
    break;
  }
  {
    auto properties = c().lock_properties();
    if (auto ok = c().start(); !ok)
      return tl::unexpected(ok.error());
  }
  loop_->set_delivering(true);
  loop_->wake_in_host(); // what durable readers kept before the start is delivered now
  start_service();
  set_state(State::Started);
  return Empty{};
}

CallResult<protocol::Empty> Host::op_stop(const Empty &, const Context &) {
  std::lock_guard lock(lifecycle_);
  if (c().state() != State::Started)
    return Empty{};
  stop_component();
  Result result;
  {
    auto properties = c().lock_properties();
    result = c().stop();
  }
  set_state(State::Stopped);
  if (!result)
    return tl::unexpected(result.error());
  return Empty{};
}

CallResult<op::StatusReply> Host::op_status(const Empty &, const Context &) {
  op::StatusReply reply{std::string(to_string(c().state())), {}};
  for (const auto &port : c().ports_) {
    op::PortStatus status{port->name(), std::string(profile::to_string(port->direction())), {}};
    for (const auto &s : port->status()) {
      op::ConnectionStatus connection;
      connection.connection = s.connection;
      connection.topic = s.topic;
      connection.matched = s.matched;
      connection.samples = s.samples;
      connection.filtered = s.filtered;
      connection.deadline_missed = s.deadline_missed;
      if (s.qos && s.qos->deadline_ns > 0)
        connection.deadline_ns = s.qos->deadline_ns;
      if (s.qos)
        connection.qos = applied_qos_message(*s.qos);
      connection.in_host = s.in_host;
      if (s.same_host)
        connection.same_host = true;
      if (s.relayed)
        connection.relayed = true;
      if (s.tcp)
        connection.tcp = true;
      status.connections.push_back(std::move(connection));
    }
    reply.ports.push_back(std::move(status));
  }
  for (const auto &port : c().resource_ports_) {
    op::PortStatus status{port->name(), "uses", {}};
    for (const auto &[connection, target] : port->targets()) {
      op::ConnectionStatus s;
      s.connection = connection;
      s.target = target.address;
      s.calls = target.calls;
      status.connections.push_back(std::move(s));
    }
    reply.ports.push_back(std::move(status));
  }
  return reply;
}

// Waits, bounded, until each named connection has matched the peers the domain expects: a
// launch starts its components only once their first samples will find their readers. Replies
// with what each connection matched; "complete" says whether all got there in time.
// The time counts from the request's arrival: in a batch for a whole host, the awaits of one
// component after another all end within the caller's timeout.
CallResult<op::AwaitMatchedReply> Host::op_await_matched(const op::AwaitMatchedRequest &r,
                                                         const Context &context) {
  std::vector<const PortBase *> ports;
  for (const auto &awaited : r.connections) {
    const PortBase *port = find_port(awaited.port);
    if (port == nullptr)
      return control::call_error(Status::NotFound, fmt::format("no port \"{}\"", awaited.port));
    ports.push_back(port);
  }
  op::AwaitMatchedReply reply{false, r.connections};
  const auto deadline = context.received + std::chrono::milliseconds(r.timeout_ms);
  auto all_matched = [&] {
    bool all = true;
    for (std::size_t i = 0; i < ports.size(); ++i) {
      auto &a = reply.connections[i];
      a.matched = ports[i]->matched(a.connection).value_or(0);
      all = all && a.matched >= a.peers;
    }
    return all;
  };
  // Discovery runs on Cyclone's threads; polling the matched counts costs nothing measurable
  // and keeps the readers' status masks (the receive loop's) untouched.
  auto pause = std::chrono::microseconds(50);
  reply.complete = all_matched();
  while (!reply.complete && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(pause);
    pause = std::min(pause * 2, std::chrono::microseconds(2000));
    reply.complete = all_matched();
  }
  return reply;
}

CallResult<protocol::Empty> Host::op_release(const Empty &, const Context &) {
  shutdown(op::Release::name);
  return Empty{};
}

} // namespace rsca::component::detail
