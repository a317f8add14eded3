#include "domain/event_channel_manager.hpp"

#include <algorithm>
#include <cctype>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "dds/port_qos.hpp"
#include "protocol/topics.hpp"

namespace rsca::domain {
namespace {

using control::Status;
using Role = ChannelMember::Role;

std::string end_of(const ChannelMember &m) {
  return fmt::format("{}/{}.{}", m.application, m.component, m.port);
}

} // namespace

std::string_view to_string(ChannelMember::Role role) {
  return role == Role::Publisher ? "publisher" : "subscriber";
}

std::string EventChannelManager::topic_of(const std::string &name) const {
  return protocol::channel_topic(domain_, name);
}

std::optional<std::string> EventChannelManager::misfit(const EventChannel &channel,
                                                       const ChannelMember &member) const {
  if (!channel.repid.empty() && !member.repid.empty() && channel.repid != member.repid)
    return fmt::format("port type: {} is {}, channel {} carries {}", end_of(member), member.repid,
                       channel.name, channel.repid);
  for (const auto &other : channel.members) {
    if (other.role == member.role)
      continue;
    const auto &publisher = member.role == Role::Publisher ? member : other;
    const auto &subscriber = member.role == Role::Publisher ? other : member;
    if (auto why = dds::qos_incompatibility(publisher.qos, subscriber.qos))
      return fmt::format("QoS: publisher {} (connection {}) and subscriber {} (connection {}) "
                         "never match on channel {}: {}",
                         end_of(publisher), publisher.connection, end_of(subscriber),
                         subscriber.connection, channel.name, *why);
  }
  return std::nullopt;
}

control::CallResult<void>
EventChannelManager::join(const std::vector<std::pair<std::string, ChannelMember>> &members) {
  std::lock_guard lock(mutex_);
  auto staged = channels_; // all or nothing
  for (const auto &[name, member] : members) {
    auto it =
        std::find_if(staged.begin(), staged.end(), [&](const auto &c) { return c.name == name; });
    if (it == staged.end())
      it = staged.insert(staged.end(), EventChannel{name, topic_of(name), "", false, {}});
    if (auto why = misfit(*it, member))
      return control::call_error(Status::BadRequest,
                                 fmt::format("connection {}: {}", member.connection, *why));
    if (it->repid.empty())
      it->repid = member.repid;
    it->members.push_back(member);
  }
  for (const auto &[name, member] : members)
    if (std::none_of(channels_.begin(), channels_.end(),
                     [&](const auto &c) { return c.name == name; }))
      spdlog::info("event channel {} created for {} (topic {})", name, member.application,
                   topic_of(name));
  channels_ = std::move(staged);
  return {};
}

std::vector<std::string> EventChannelManager::leave(const std::string &application) {
  std::lock_guard lock(mutex_);
  std::vector<std::string> destroyed;
  for (auto &c : channels_)
    std::erase_if(c.members, [&](const auto &m) { return m.application == application; });
  std::erase_if(channels_, [&](const EventChannel &c) {
    if (!c.members.empty() || c.operator_owned)
      return false;
    destroyed.push_back(c.name);
    spdlog::info("event channel {} destroyed: its last member ({}) left", c.name, application);
    return true;
  });
  return destroyed;
}

control::CallResult<EventChannel> EventChannelManager::create(const std::string &name) {
  if (name.empty())
    return control::call_error(Status::BadRequest, "a channel needs a name");
  std::lock_guard lock(mutex_);
  auto it = std::find_if(channels_.begin(), channels_.end(),
                         [&](const auto &c) { return c.name == name; });
  if (it == channels_.end())
    it = channels_.insert(channels_.end(), EventChannel{name, topic_of(name), "", true, {}});
  it->operator_owned = true;
  spdlog::info("event channel {} created by an operator", name);
  return *it;
}

control::CallResult<void> EventChannelManager::destroy(const std::string &name) {
  std::lock_guard lock(mutex_);
  auto it = std::find_if(channels_.begin(), channels_.end(),
                         [&](const auto &c) { return c.name == name; });
  if (it == channels_.end())
    return control::call_error(Status::NotFound, fmt::format("no event channel {}", name));
  if (!it->members.empty()) {
    std::vector<std::string> apps;
    for (const auto &m : it->members)
      if (std::find(apps.begin(), apps.end(), m.application) == apps.end())
        apps.push_back(m.application);
    return control::call_error(Status::Rejected,
                               fmt::format("event channel {} is in use by {}; release them first",
                                           name, fmt::join(apps, ", ")));
  }
  channels_.erase(it);
  spdlog::info("event channel {} destroyed by an operator", name);
  return {};
}

std::vector<EventChannel> EventChannelManager::list() const {
  std::lock_guard lock(mutex_);
  return channels_;
}

std::optional<EventChannel> EventChannelManager::find(const std::string &name) const {
  std::lock_guard lock(mutex_);
  for (const auto &c : channels_)
    if (c.name == name)
      return c;
  return std::nullopt;
}

} // namespace rsca::domain
