// The component.* operations: what the domain (and a component's uses port of a control
// interface) asks of a component, served by the component runtime (component/host.cpp).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "protocol/codec.hpp"
#include "protocol/node_ops.hpp"

namespace rsca::protocol::component {

// A same-host connection's ring in the host's arena (shm/ring.hpp), which the node that relays
// the request makes and names: its offset, and a reader's slot in it.
struct Ring {
  std::uint64_t offset = 0;
  std::uint32_t slot = 0; // a provides port's
  static constexpr auto fields() {
    return std::tuple{required("offset", &Ring::offset), optional("slot", &Ring::slot)};
  }
};

// The end of a connection this component's port is to be: its topic (a DDS connection) or its
// target (a uses port of a control interface, which calls that component's control address).
struct ConnectRequest {
  std::string connection; // unique per port
  std::string port;
  std::string direction; // "uses" or "provides"
  std::string repid;
  std::optional<std::string> topic;  // a DDS connection
  std::optional<Json> qos;           // dds/port_qos.hpp's JSON form
  std::optional<std::string> filter; // a provides port's content filter
  std::optional<bool> local;         // both ends are in this process: no DDS
  std::optional<std::string> target; // a control interface's component address
  std::optional<std::string> via;    // the endpoint that serves `target` (its node or host)
  // Both ends are processes of one node, which relays the request (the domain says so): the node
  // then makes the topic's ring and adds `ring`, and the connection goes through it, not DDS.
  std::optional<bool> shared_memory;
  // With shared_memory: the connection has (or may have) ends on other hosts, which the node
  // reaches by relaying the ring to and from DDS (node/topic_bridge.hpp). The process sees a ring.
  std::optional<bool> relay;
  std::optional<Ring> ring;
  // transport="tcp" (profile/assembly.hpp): the writer connects to the reader's `tcp_peer`
  // ("address:port", what the reader's connect replied) and first sends `tcp_token`, which the
  // reader checks: a stream from anyone else on the network is closed unread.
  std::optional<std::string> tcp_peer;
  std::optional<std::string> tcp_token;
  static constexpr auto fields() {
    using R = ConnectRequest;
    return std::tuple{required("connection", &R::connection),
                      required("port", &R::port),
                      required("direction", &R::direction),
                      optional("repid", &R::repid),
                      optional("topic", &R::topic),
                      optional("qos", &R::qos),
                      optional("filter", &R::filter),
                      optional("local", &R::local),
                      optional("target", &R::target),
                      optional("via", &R::via),
                      optional("shared_memory", &R::shared_memory),
                      optional("relay", &R::relay),
                      optional("ring", &R::ring),
                      optional("tcp_peer", &R::tcp_peer),
                      optional("tcp_token", &R::tcp_token)};
  }
};

// A provides port's connection over TCP answers where its writer connects ("address:port").
struct ConnectReply {
  std::optional<std::string> tcp_endpoint;
  static constexpr auto fields() {
    return std::tuple{optional("tcp_endpoint", &ConnectReply::tcp_endpoint)};
  }
};

struct DisconnectRequest {
  std::string connection;
  std::string port;
  static constexpr auto fields() {
    return std::tuple{required("connection", &DisconnectRequest::connection),
                      required("port", &DisconnectRequest::port)};
  }
};

struct ConfigureRequest {
  Json properties = Json::object(); // property id -> value (profile/property_json.hpp)
  static constexpr auto fields() {
    return std::tuple{required("properties", &ConfigureRequest::properties)};
  }
};

struct QueryRequest {
  std::vector<std::string> ids; // none: every property
  static constexpr auto fields() { return std::tuple{optional("ids", &QueryRequest::ids)}; }
};

struct QueryReply {
  Json properties = Json::object();
  static constexpr auto fields() {
    return std::tuple{required("properties", &QueryReply::properties)};
  }
};

// The QoS one end of a connection applies, read back from its live transport (a DDS entity's
// own QoS, or a ring's, TCP stream's or in-host queue's settings); names as a SAD's <qos> has
// them ("reliable", "keeplast", "transientlocal", "exclusive", "manualbytopic").
struct AppliedQos {
  std::string reliability;
  std::string history;
  std::int32_t depth = 0; // keeplast: the samples kept
  std::string durability;
  std::string ownership;
  std::int64_t deadline_ns = 0; // 0: none
  std::string liveliness;
  std::int64_t lease_ns = 0; // 0: none
  static constexpr auto fields() {
    using R = AppliedQos;
    return std::tuple{required("reliability", &R::reliability),
                      required("history", &R::history),
                      required("depth", &R::depth),
                      required("durability", &R::durability),
                      required("ownership", &R::ownership),
                      required("deadline_ns", &R::deadline_ns),
                      required("liveliness", &R::liveliness),
                      required("lease_ns", &R::lease_ns)};
  }
};

// One connection of a port, as the component sees it.
struct ConnectionStatus {
  std::string connection;
  std::optional<std::string> topic;
  std::optional<std::int64_t> matched;
  std::optional<std::uint64_t> samples;
  std::optional<std::uint64_t> filtered;
  std::optional<std::uint64_t> deadline_missed;
  std::optional<std::int64_t> deadline_ns; // the end's deadline; absent: none
  std::optional<bool> in_host;
  std::optional<bool> same_host;
  std::optional<bool> relayed;       // same_host, and the node relays it to other hosts
  std::optional<bool> tcp;           // a TCP stream between the two ends (transport="tcp")
  std::optional<std::string> target; // a control interface's connection: whom it calls
  std::optional<std::uint64_t> calls;
  std::optional<AppliedQos> qos; // the end's, as its transport applies it
  static constexpr auto fields() {
    using R = ConnectionStatus;
    return std::tuple{
        required("connection", &R::connection),   optional("topic", &R::topic),
        optional("matched", &R::matched),         optional("samples", &R::samples),
        optional("filtered", &R::filtered),       optional("deadline_missed", &R::deadline_missed),
        optional("in_host", &R::in_host),         optional("same_host", &R::same_host),
        optional("relayed", &R::relayed),         optional("tcp", &R::tcp),
        optional("target", &R::target),           optional("calls", &R::calls),
        optional("deadline_ns", &R::deadline_ns), optional("qos", &R::qos)};
  }
};

struct PortStatus {
  std::string name;
  std::string direction;
  std::vector<ConnectionStatus> connections;
  static constexpr auto fields() {
    return std::tuple{required("name", &PortStatus::name),
                      required("direction", &PortStatus::direction),
                      required("connections", &PortStatus::connections)};
  }
};

struct StatusReply {
  std::string state;
  std::vector<PortStatus> ports;
  static constexpr auto fields() {
    return std::tuple{required("state", &StatusReply::state),
                      required("ports", &StatusReply::ports)};
  }
};

// What a component announces (announcement kind "component") when it registers and at each
// change of its state. The domain takes a component for registered on it; an announcement that
// does not decode is not taken (component/host.cpp builds it, domain/domain_connections.cpp
// reads it).
struct Announcement {
  std::string id;          // the component instance's id in its SAD
  std::string name;        // its usage name
  std::string application; // the application's name
  std::int64_t pid = 0;    // the process it runs in (a component host's, when hosted)
  std::string state;       // the runtime's lifecycle state (component/component.hpp), for people
  std::vector<node::DevicePort> ports;
  // The endpoint that serves the component's address: its node, which relays to it and adds
  // this (control/server.hpp's kAnnouncedVia). Absent: the component serves it itself.
  std::optional<std::string> via;
  static constexpr auto fields() {
    using R = Announcement;
    return std::tuple{required("id", &R::id),
                      required("name", &R::name),
                      required("application", &R::application),
                      required("pid", &R::pid),
                      required("state", &R::state),
                      required("ports", &R::ports),
                      optional("via", &R::via)};
  }
};

// A connection whose peers the caller waits for: `peers` matched readers or writers.
struct AwaitedConnection {
  std::string port;
  std::string connection;
  std::int32_t peers = 1;
  std::int32_t matched = 0; // in the reply
  static constexpr auto fields() {
    using R = AwaitedConnection;
    return std::tuple{required("port", &R::port), required("connection", &R::connection),
                      optional("peers", &R::peers), optional("matched", &R::matched)};
  }
};

struct AwaitMatchedRequest {
  std::vector<AwaitedConnection> connections;
  std::int64_t timeout_ms = 2000; // counted from the request's arrival
  static constexpr auto fields() {
    return std::tuple{required("connections", &AwaitMatchedRequest::connections),
                      optional("timeout_ms", &AwaitMatchedRequest::timeout_ms)};
  }
};

struct AwaitMatchedReply {
  bool complete = false; // every connection matched its peers in time
  std::vector<AwaitedConnection> connections;
  static constexpr auto fields() {
    return std::tuple{required("complete", &AwaitMatchedReply::complete),
                      required("connections", &AwaitMatchedReply::connections)};
  }
};

struct Initialize {
  static constexpr std::string_view name = "component.initialize";
  using Request = Empty;
  using Reply = Empty;
};
struct Configure {
  static constexpr std::string_view name = "component.configure";
  using Request = ConfigureRequest;
  using Reply = Empty;
};
struct Query {
  static constexpr std::string_view name = "component.query";
  using Request = QueryRequest;
  using Reply = QueryReply;
};
struct Connect {
  static constexpr std::string_view name = "component.connect";
  using Request = ConnectRequest;
  using Reply = ConnectReply;
};
struct Disconnect {
  static constexpr std::string_view name = "component.disconnect";
  using Request = DisconnectRequest;
  using Reply = Empty;
};
struct Start {
  static constexpr std::string_view name = "component.start";
  using Request = Empty;
  using Reply = Empty;
};
struct Stop {
  static constexpr std::string_view name = "component.stop";
  using Request = Empty;
  using Reply = Empty;
};
struct Status {
  static constexpr std::string_view name = "component.status";
  using Request = Empty;
  using Reply = StatusReply;
};
struct AwaitMatched {
  static constexpr std::string_view name = "component.await_matched";
  using Request = AwaitMatchedRequest;
  using Reply = AwaitMatchedReply;
};
struct Release {
  static constexpr std::string_view name = "component.release";
  using Request = Empty;
  using Reply = Empty;
};

} // namespace rsca::protocol::component
