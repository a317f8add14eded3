// EventChannelManager: the domain's event channels. A channel named in a SAD
// (findby/domainfinder type="eventchannel") is created when its first member joins, shared by
// every application that names it, and destroyed when the last member leaves, unless an
// operator created it (`rsca channel create`), in which case it lives until destroyed.
//
// A channel is one DDS topic per domain; its members are the publishers' writers and the
// subscribers' readers, made by the components at connect time and deleted at disconnect. The
// manager keeps the membership, refuses a member whose port type or QoS could never match the
// others (before anything runs), and hands out the topic.
#pragma once

#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "control/endpoint.hpp"
#include "profile/assembly.hpp"

namespace rsca::domain {

struct ChannelMember {
  enum class Role : std::uint8_t { Publisher, Subscriber };
  Role role = Role::Publisher;
  std::string application;
  std::string connection; // the SAD connection id
  std::string component;
  std::string port;
  std::string repid;
  profile::ConnectionQos qos;
  std::string filter; // subscribers: only events matching it are delivered
};
std::string_view to_string(ChannelMember::Role role);

struct EventChannel {
  std::string name;
  std::string topic;
  std::string repid; // empty until a member with a port type joins
  bool operator_owned = false;
  std::vector<ChannelMember> members;
};

class EventChannelManager {
public:
  explicit EventChannelManager(std::string domain) : domain_(std::move(domain)) {}

  // The DDS topic of channel `name` in this domain: unique per domain, so that domains never
  // share a channel.
  std::string topic_of(const std::string &name) const;

  // Adds every member of one application, creating channels on first use; all or nothing. A
  // member whose port type differs from the channel's, or whose QoS cannot match a member of
  // the other role, is refused with the connection, both ends and the rule broken.
  control::CallResult<void> join(const std::vector<std::pair<std::string, ChannelMember>> &members);
  // Removes an application's members; returns the channels that went with them.
  std::vector<std::string> leave(const std::string &application);

  control::CallResult<EventChannel> create(const std::string &name);
  // Destroys an operator's channel that no application uses.
  control::CallResult<void> destroy(const std::string &name);

  std::vector<EventChannel> list() const;
  std::optional<EventChannel> find(const std::string &name) const;

private:
  std::optional<std::string> misfit(const EventChannel &channel, const ChannelMember &member) const;

  std::string domain_;
  mutable std::mutex mutex_;
  std::vector<EventChannel> channels_; // in order of creation
};

} // namespace rsca::domain
