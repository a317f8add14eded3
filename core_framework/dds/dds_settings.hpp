// Which DDS domain a process joins and how: the domain id isolates runs (each test domain uses
// its own), the rest fills in the project's Cyclone configuration (cyclonedds.xml).
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace rsca::dds {

struct DdsSettings {
  std::uint32_t domain_id = 0;
  std::string interface_name = "lo";
  // Empty: discovery by multicast on the interface (loopback included). An address: unicast
  // discovery to that peer instead, for networks without multicast; every participant of the
  // host then takes one of `max_participants` indexes, and each announcement goes to all of them.
  std::string peer;
  std::uint32_t max_participants = 600;
  // This participant's lease: how soon others notice it died. The daemons' 1 s is what makes a
  // dead node visible within a second.
  std::chrono::milliseconds lease{1000};
  // The lease a node gives the component processes it starts. A component's death is seen at once
  // by its node (it is the parent) and a component dies with its node, so a short lease would buy
  // nothing; it would cost much: the liveliness traffic of a participant goes to every other one
  // at a rate set by its lease, and a hundred idle processes with 1 s leases took a core (6 % of
  // one with 10 s, measured with tests/bench idle processes after discovery settled).
  std::chrono::milliseconds component_lease{10000};
  std::string trace = "warning";
  // Cyclone's discovery tag: participants only discover those with the same domain id and tag.
  // Tests and benchmarks give each run one of its own, so runs that happen to share a domain id
  // never meet. Letters, digits, '-' and '_' only.
  std::string tag;

  // Defaults overridden by RSCA_DDS_DOMAIN, RSCA_DDS_INTERFACE, RSCA_DDS_PEER, RSCA_DDS_LEASE_MS,
  // RSCA_DDS_COMPONENT_LEASE_MS, RSCA_DDS_TRACE, RSCA_DDS_TAG.
  static DdsSettings from_environment();
  // The variables that make a child process join the same domain with the same settings.
  std::vector<std::pair<std::string, std::string>> environment() const;
  // The same for a component process: its lease is `component_lease`.
  std::vector<std::pair<std::string, std::string>> component_environment() const;
};

// The Cyclone XML configuration for these settings.
std::string cyclone_config(const DdsSettings &settings);

} // namespace rsca::dds
