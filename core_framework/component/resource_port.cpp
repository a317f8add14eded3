#include "component/resource_port.hpp"

#include <fmt/format.h>

#include "control/operation.hpp"
#include "protocol/component_ops.hpp"

namespace rsca::component {

namespace op = protocol::component;

std::map<std::string, ResourceUsesPort::Target> ResourceUsesPort::targets() const {
  std::lock_guard lock(mutex_);
  return targets_;
}

void ResourceUsesPort::connect(const std::string &connection, const std::string &target,
                               std::weak_ptr<control::Server> endpoint) {
  std::lock_guard lock(mutex_);
  targets_[connection] = Target{target, 0};
  endpoint_ = std::move(endpoint);
}

bool ResourceUsesPort::disconnect(const std::string &connection) {
  std::lock_guard lock(mutex_);
  return targets_.erase(connection) != 0;
}

void ResourceUsesPort::disconnect_all() {
  std::lock_guard lock(mutex_);
  targets_.clear();
}

template <typename Op>
control::CallResult<std::map<std::string, typename Op::Reply>>
ResourceUsesPort::call_each(const typename Op::Request &request,
                            std::chrono::milliseconds timeout) {
  std::map<std::string, Target> targets;
  std::shared_ptr<control::Server> endpoint;
  {
    // The calls run without the lock: a disconnect meanwhile does not wait for them.
    std::lock_guard lock(mutex_);
    targets = targets_;
    endpoint = endpoint_.lock();
  }
  std::map<std::string, typename Op::Reply> replies;
  if (targets.empty())
    return replies;
  if (!endpoint)
    return control::call_error(control::Status::Unavailable,
                               fmt::format("port {}: the component is shutting down", name_));
  for (const auto &[connection, target] : targets) {
    {
      // Removed since the snapshot (a disconnect, the component's release): not called.
      std::lock_guard lock(mutex_);
      auto it = targets_.find(connection);
      if (it == targets_.end())
        continue;
      ++it->second.calls;
    }
    auto reply = control::call<Op>(*endpoint, target.address, request, timeout);
    if (!reply)
      return control::call_error(reply.error().status,
                                 fmt::format("port {}, connection {}: {} to {}: {}", name_,
                                             connection, Op::name, target.address,
                                             reply.error().message));
    replies.emplace(connection, std::move(*reply));
  }
  return replies;
}

control::CallResult<void> ResourceUsesPort::configure(const nlohmann::json &properties,
                                                      std::chrono::milliseconds timeout) {
  return call_each<op::Configure>({properties}, timeout).map([](auto &&) {});
}

control::CallResult<std::map<std::string, nlohmann::json>>
ResourceUsesPort::query(const std::vector<std::string> &ids, std::chrono::milliseconds timeout) {
  auto replies = call_each<op::Query>({ids}, timeout);
  if (!replies)
    return tl::unexpected(replies.error());
  std::map<std::string, nlohmann::json> properties;
  for (auto &[connection, reply] : *replies)
    properties.emplace(connection, std::move(reply.properties));
  return properties;
}

control::CallResult<void> ResourceUsesPort::start(std::chrono::milliseconds timeout) {
  return call_each<op::Start>({}, timeout).map([](auto &&) {});
}

control::CallResult<void> ResourceUsesPort::stop(std::chrono::milliseconds timeout) {
  return call_each<op::Stop>({}, timeout).map([](auto &&) {});
}

} // namespace rsca::component
