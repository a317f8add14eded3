// The wiring service: the one way the domain makes and unmakes connections between ports, for a
// launch (its SAD's connections and event-channel memberships) and for the ConnectionManager
// (runtime connections). Its callers resolve each end to what serves it; the service connects
// every reader first, then every writer (so that the first samples written find their readers),
// then waits until each end has matched the peers it expects, so that nothing written once the
// components start is lost to discovery still under way. Both ends in one component host take
// the in-host path (no DDS); a reader gets the connection's content filter.
#pragma once

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "control/caller.hpp"

namespace rsca::domain {

// One end of a connection as its owner serves it.
struct WireEnd {
  std::string address;    // the owner's control address
  std::string port;       // the owner's port
  std::string connection; // the id the owner knows the connection by
  std::string host;       // the component host that serves the owner, when it is hosted
  int peers = 1;          // the ends on the other side it must match (0: none to wait for)
  std::string what;       // for messages: "sad_1 (Producer_1.out)"
  std::string node;       // the node that relays to the owner, a process it started; or empty
};

struct Wire {
  // An event channel's member has one end: the other side is the channel's other members.
  std::optional<WireEnd> uses;
  std::optional<WireEnd> provides;
  // Empty: a uses port calling a component's supported interface at `interface_target`.
  std::string topic;
  std::string interface_target;
  std::string interface_via; // the endpoint that serves interface_target; empty: itself
  std::string repid;
  nlohmann::json qos; // dds/port_qos.hpp's JSON form
  std::string filter; // the reader's content filter
  bool to_interface() const { return topic.empty(); }
  // Both ends are components of one component host: the connection bypasses DDS.
  bool in_one_host() const {
    return uses && provides && !uses->host.empty() && uses->host == provides->host;
  }
  // Both ends are processes one node started, in two processes: unless its QoS asks for direct
  // DDS, the connection goes through that node's shared memory (node/host_data.hpp).
  bool on_one_node() const {
    return uses && provides && !uses->node.empty() && uses->node == provides->node &&
           !in_one_host();
  }
  // `end` is a process a node relays for, not in one host with its peer: unless the QoS asks
  // for direct DDS, its data goes through that node's shared memory, and through the node's
  // relay to the ends on other hosts (node/topic_bridge.hpp).
  bool through_node(const WireEnd &end) const { return !end.node.empty() && !in_one_host(); }
};

// How long each phase of a connect took, for the launch's progress.
struct WiringTimes {
  double readers_ms = 0;
  double writers_ms = 0;
  double matched_ms = 0;
};

class Wiring {
public:
  Wiring(control::Caller &caller, std::chrono::milliseconds timeout)
      : caller_(caller), timeout_(timeout) {}

  // Connects every wire and waits until each end has matched its peers; stops at the first
  // failure. `made` receives every end connected, also on failure: what the caller undoes.
  control::CallResult<WiringTimes> connect(const std::vector<Wire> &wires,
                                           std::vector<WireEnd> &made);

  // Disconnects the ends, all at once; what failed, each named ("sad_1 (gps.out): timeout").
  std::vector<std::string> disconnect(const std::vector<WireEnd> &ends);

private:
  control::CallResult<void> await_matched(const std::vector<Wire> &wires);

  control::Caller &caller_;
  std::chrono::milliseconds timeout_;
};

} // namespace rsca::domain
