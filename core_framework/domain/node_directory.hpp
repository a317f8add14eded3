// The domain's directory of nodes: what each node daemon last announced of itself and its
// devices (protocol/node_ops.hpp), by node name. It owns that state alone, under its own lock;
// readers get copies.
#pragma once

#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "protocol/node_ops.hpp"

namespace rsca::domain {

class NodeDirectory {
public:
  struct Node {
    std::string address;
    protocol::node::NodeAnnouncement announcement; // announcement.node is its name
  };

  // An endpoint that announced itself as a node with an announcement that does not fit the
  // contract (another version of rsca, or not rsca at all): listed, never used.
  struct Refused {
    std::string address;
    std::string why;
  };
  // At most this many are kept: the announcements come from the network.
  static constexpr std::size_t kMaxRefused = 64;

  // Records what the node at `address` announced; true when the node is new.
  bool alive(const std::string &address, protocol::node::NodeAnnouncement announcement);
  // Records that the node at `address` was refused, and why; false when it was already.
  bool refused(const std::string &address, std::string why);
  // The node at `address` left: its record, now dropped, and kept as lost when `lost` (it may be
  // back); nothing for an address no node has.
  std::optional<Node> gone(const std::string &address, bool lost);
  // The record of the node `name` when it was lost, taken (it is back); nothing if it was not.
  std::optional<Node> take_lost(const std::string &name);

  bool contains(const std::string &node) const;
  std::optional<std::string> address_of(const std::string &node) const;
  // The node relays the control of the processes it starts (protocol/node_link.hpp).
  bool relays_processes(const std::string &node) const;
  // The device of that id ("NODE:LABEL").
  std::optional<protocol::node::DeviceRecord> device(const std::string &id) const;
  std::vector<Node> snapshot() const;
  // The nodes lost and not back, as they last announced themselves.
  std::vector<Node> lost_nodes() const;
  std::vector<Refused> refused_nodes() const;

private:
  const protocol::node::DeviceRecord *find_device(const std::string &id) const;

  mutable std::mutex mutex_;
  std::map<std::string, Node> nodes_;          // by name
  std::map<std::string, std::string> refused_; // why, by address
  std::map<std::string, Node> lost_;           // by name, until it is back
};

} // namespace rsca::domain
