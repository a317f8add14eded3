// The channel.* and connection.* operations: the domain's event channels, and the connections of
// running applications and of the operator (`rsca connect`), as the CLI asks the domain daemon
// for them.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include "protocol/codec.hpp"
#include "protocol/domain_ops.hpp"

namespace rsca::protocol {
namespace connection {
// Pending: an end is not there yet, or is there and has not matched its peer. Failed: an end's
// owner is gone (its process exited, or its node is lost).
enum class ConnectionState : std::uint8_t { Connected, Pending, Failed };
} // namespace connection

template <>
struct EnumNames<connection::ConnectionState> {
  static constexpr std::array names{std::pair{connection::ConnectionState::Connected, "connected"},
                                    std::pair{connection::ConnectionState::Pending, "pending"},
                                    std::pair{connection::ConnectionState::Failed, "failed"}};
};

} // namespace rsca::protocol

namespace rsca::protocol::connection {

using domain::Named;

struct ChannelMemberView {
  std::string role; // "publisher" or "subscriber"
  std::string application;
  std::string connection; // the SAD connection id
  std::string component;
  std::string port;
  std::string filter; // a subscriber's content filter; empty: none
  static constexpr auto fields() {
    using R = ChannelMemberView;
    return std::tuple{required("role", &R::role),
                      required("application", &R::application),
                      required("connection", &R::connection),
                      required("component", &R::component),
                      required("port", &R::port),
                      required("filter", &R::filter)};
  }
};

struct ChannelView {
  std::string name;
  std::string topic;
  std::string repid; // empty until a member with a port type joins
  bool operator_owned = false;
  std::uint64_t publishers = 0;
  std::uint64_t subscribers = 0;
  std::vector<ChannelMemberView> members;
  static constexpr auto fields() {
    using R = ChannelView;
    return std::tuple{required("name", &R::name),
                      required("topic", &R::topic),
                      required("repid", &R::repid),
                      required("operator", &R::operator_owned),
                      required("publishers", &R::publishers),
                      required("subscribers", &R::subscribers),
                      required("members", &R::members)};
  }
};

struct ChannelsReply {
  std::vector<ChannelView> channels;
  static constexpr auto fields() {
    return std::tuple{required("channels", &ChannelsReply::channels)};
  }
};

// An end as the operator names it: a component's port (application, component, port), an
// application's external port (application, port) or a device's (device, port).
struct PortEnd {
  std::optional<std::string> application;
  std::optional<std::string> component;
  std::optional<std::string> device;
  std::string port;
  static constexpr auto fields() {
    using R = PortEnd;
    return std::tuple{optional("application", &R::application),
                      optional("component", &R::component), optional("device", &R::device),
                      required("port", &R::port)};
  }
};

// A runtime connection as the operator asks for it; the domain keeps it in this form in its
// store, to make it again after a restart.
struct CreateRequest {
  PortEnd uses;
  PortEnd provides;
  std::optional<std::string> id;     // absent: runtime_N
  Json qos = Json::object();         // the SAD's <qos> names; defaults filled in by the domain
  std::optional<std::string> filter; // the provides end's content filter
  static constexpr auto fields() {
    using R = CreateRequest;
    return std::tuple{required("uses", &R::uses), required("provides", &R::provides),
                      optional("id", &R::id), optional("qos", &R::qos),
                      optional("filter", &R::filter)};
  }
};

// A connection as both an application's and a runtime one show it.
struct ConnectionView {
  std::string id;
  std::string uses; // "owner.port"; empty: an event channel's publisher side
  std::string provides;
  std::string topic; // empty: a uses port calling a component's supported interface
  std::string repid;
  Json qos = Json::object(); // dds/port_qos.hpp's JSON form
  static constexpr auto fields() {
    using R = ConnectionView;
    return std::tuple{required("id", &R::id),
                      required("uses", &R::uses),
                      required("provides", &R::provides),
                      required("topic", &R::topic),
                      required("repid", &R::repid),
                      required("qos", &R::qos)};
  }
};

// A runtime connection just made.
struct CreateReply : ConnectionView {
  ConnectionState state = ConnectionState::Connected;
  std::optional<std::string> waiting_for; // a pending one: what for
  bool persisted = false;                 // kept in the store: it outlasts a restart
  std::optional<std::string> filter;      // its provides end's content filter
  static constexpr auto fields() {
    using R = CreateReply;
    return std::tuple_cat(
        ConnectionView::fields(),
        std::tuple{required("state", &R::state), optional("waiting_for", &R::waiting_for),
                   required("persisted", &R::persisted), optional("filter", &R::filter)});
  }
};

// One connection in connection.list, with each end's live state as its owner reports it
// ({"matched", "samples", "filtered", "deadline_missed", "in_host", "same_host",
// "relayed", "tcp", and "deadline_ns" when the end has a deadline}, or {"calls"}
// for a caller of a supported interface), null when the end shows none: JSON, so that null stays
// null.
struct ListedConnection : ConnectionView {
  std::string application;                // "(runtime)" for the operator's
  std::optional<std::string> filter;      // an application's connection
  std::optional<ConnectionState> state;   // a runtime connection
  std::optional<std::string> waiting_for; // a pending runtime connection
  Json uses_state;
  Json provides_state;
  static constexpr auto fields() {
    using R = ListedConnection;
    return std::tuple_cat(ConnectionView::fields(),
                          std::tuple{required("application", &R::application),
                                     optional("filter", &R::filter), optional("state", &R::state),
                                     optional("waiting_for", &R::waiting_for),
                                     required("uses_state", &R::uses_state),
                                     required("provides_state", &R::provides_state)});
  }
};

struct ListRequest {
  std::string app; // empty: every application's, and every runtime connection
  static constexpr auto fields() { return std::tuple{optional("app", &ListRequest::app)}; }
};

struct ListReply {
  std::vector<ListedConnection> connections;
  static constexpr auto fields() {
    return std::tuple{required("connections", &ListReply::connections)};
  }
};

// A request or reply that names one runtime connection.
struct ConnectionId {
  std::string id;
  static constexpr auto fields() { return std::tuple{required("id", &ConnectionId::id)}; }
};

struct ListChannels {
  static constexpr std::string_view name = "channel.list";
  using Request = Empty;
  using Reply = ChannelsReply;
};
struct CreateChannel {
  static constexpr std::string_view name = "channel.create";
  using Request = Named;
  using Reply = ChannelView;
};
struct DestroyChannel {
  static constexpr std::string_view name = "channel.destroy";
  using Request = Named;
  using Reply = Named;
};
struct List {
  static constexpr std::string_view name = "connection.list";
  using Request = ListRequest;
  using Reply = ListReply;
};
struct Create {
  static constexpr std::string_view name = "connection.create";
  using Request = CreateRequest;
  using Reply = CreateReply;
};
struct Destroy {
  static constexpr std::string_view name = "connection.destroy";
  using Request = ConnectionId;
  using Reply = ConnectionId;
};

} // namespace rsca::protocol::connection
