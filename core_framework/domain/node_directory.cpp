#include "domain/node_directory.hpp"

#include <algorithm>

namespace rsca::domain {

bool NodeDirectory::alive(const std::string &address,
                          protocol::node::NodeAnnouncement announcement) {
  std::lock_guard lock(mutex_);
  refused_.erase(address); // it announced again, within the contract this time
  const std::string name = announcement.node;
  const bool known = nodes_.count(name) != 0;
  nodes_[name] = Node{address, std::move(announcement)};
  return !known;
}

bool NodeDirectory::refused(const std::string &address, std::string why) {
  std::lock_guard lock(mutex_);
  auto it = refused_.find(address);
  if (it != refused_.end()) {
    it->second = std::move(why);
    return false;
  }
  if (refused_.size() < kMaxRefused)
    refused_.emplace(address, std::move(why));
  return true;
}

std::vector<NodeDirectory::Refused> NodeDirectory::refused_nodes() const {
  std::lock_guard lock(mutex_);
  std::vector<Refused> out;
  for (const auto &[address, why] : refused_)
    out.push_back({address, why});
  return out;
}

std::optional<NodeDirectory::Node> NodeDirectory::gone(const std::string &address, bool lost) {
  std::lock_guard lock(mutex_);
  refused_.erase(address);
  auto it = std::find_if(nodes_.begin(), nodes_.end(),
                         [&](const auto &n) { return n.second.address == address; });
  if (it == nodes_.end())
    return std::nullopt;
  Node node = std::move(it->second);
  nodes_.erase(it);
  if (lost)
    lost_[node.announcement.node] = node; // one per name: bounded by the nodes there were
  else
    lost_.erase(node.announcement.node);
  return node;
}

std::optional<NodeDirectory::Node> NodeDirectory::take_lost(const std::string &name) {
  std::lock_guard lock(mutex_);
  auto it = lost_.find(name);
  if (it == lost_.end())
    return std::nullopt;
  Node node = std::move(it->second);
  lost_.erase(it);
  return node;
}

bool NodeDirectory::contains(const std::string &node) const {
  std::lock_guard lock(mutex_);
  return nodes_.count(node) != 0;
}

std::optional<std::string> NodeDirectory::address_of(const std::string &node) const {
  std::lock_guard lock(mutex_);
  auto it = nodes_.find(node);
  if (it == nodes_.end())
    return std::nullopt;
  return it->second.address;
}

bool NodeDirectory::relays_processes(const std::string &node) const {
  std::lock_guard lock(mutex_);
  auto it = nodes_.find(node);
  return it != nodes_.end() && it->second.announcement.relays_processes.value_or(false);
}

std::optional<protocol::node::DeviceRecord> NodeDirectory::device(const std::string &id) const {
  std::lock_guard lock(mutex_);
  const auto *device = find_device(id);
  if (device == nullptr)
    return std::nullopt;
  return *device;
}

namespace {

std::vector<NodeDirectory::Node> nodes_of(const std::map<std::string, NodeDirectory::Node> &map) {
  std::vector<NodeDirectory::Node> out;
  out.reserve(map.size());
  for (const auto &[name, node] : map)
    out.push_back(node);
  return out;
}

} // namespace

std::vector<NodeDirectory::Node> NodeDirectory::snapshot() const {
  std::lock_guard lock(mutex_);
  return nodes_of(nodes_);
}

std::vector<NodeDirectory::Node> NodeDirectory::lost_nodes() const {
  std::lock_guard lock(mutex_);
  return nodes_of(lost_);
}

// Called with mutex_ held.
const protocol::node::DeviceRecord *NodeDirectory::find_device(const std::string &id) const {
  const auto colon = id.find(':');
  if (colon == std::string::npos)
    return nullptr;
  auto node = nodes_.find(id.substr(0, colon));
  if (node == nodes_.end())
    return nullptr;
  for (const auto &d : node->second.announcement.devices)
    if (d.id == id)
      return &d;
  return nullptr;
}

} // namespace rsca::domain
