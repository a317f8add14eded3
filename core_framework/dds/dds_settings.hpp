// Which DDS domain a process joins and how: the domain id isolates runs (each test domain uses
// its own), the rest fills in the project's Cyclone configuration (cyclonedds.xml).
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace rsca::dds {

// Cyclone's discovery port for domain id d is 7400 + 250 x d. Up to this id it lies below the
// kernel's ephemeral ports (from 32768), which any other process's socket may hold first. Tests,
// benchmarks and the demo pick their ids up to it (tests/bench/local_domain.py and tools/demo
// say the same in their languages).
inline constexpr std::uint32_t kFirstDiscoveryPort = 7400;
inline constexpr std::uint32_t kDiscoveryPortsPerDomain = 250;
inline constexpr std::uint32_t kFirstEphemeralPort = 32768;
inline constexpr std::uint32_t kLastPortSafeDomainId =
    (kFirstEphemeralPort - 1 - kFirstDiscoveryPort) / kDiscoveryPortsPerDomain;
static_assert(kLastPortSafeDomainId == 101);

struct DdsSettings {
  std::uint32_t domain_id = 0;
  std::string interface_name = "lo";
  // Empty: discovery by multicast on the interface (loopback included). An address: unicast
  // discovery to that peer instead, for networks without multicast; every participant of the
  // host then takes one of `max_participants` indexes, and each announcement goes to all of them.
  std::string peer;
  std::uint32_t max_participants = 600;
  // How a participant's liveliness and reliability are timed. The daemons and the CLI use
  // `timing`; the component processes a node starts use `component_timing`, because they are many
  // and each is watched by its node anyway.
  struct Timing {
    // How soon others notice the participant died. The daemons' 1 s is what makes a dead node
    // visible within a second. A component's death is seen at once by its node (it is the parent)
    // and a component dies with its node, so a short lease would buy it nothing and cost much:
    // liveliness traffic goes to every other participant at a rate set by the lease, and a
    // hundred idle processes with 1 s leases took a core (6 % of one with 10 s, measured with
    // tests/bench idle processes after discovery settled).
    std::chrono::milliseconds lease;
    // How often a reliable writer with unacknowledged samples sends heartbeats (Cyclone backs off
    // while nothing new is written). Short makes a request that raced discovery arrive sooner,
    // which the daemons' requests need. But each heartbeat goes to every matched reader as a
    // datagram of its own and each newcomer leaves every participant's discovery writers
    // unacknowledged: a hundred component processes at 10 ms were a storm that stalled their
    // launch (docs/architecture.md).
    std::chrono::milliseconds heartbeat;
    // How long deleting a writer waits for its last samples to be acknowledged. A component is
    // deleted when its application is released, once it has confirmed the release; with its
    // slower heartbeat, Cyclone's 1 s default made every release wait for one more heartbeat.
    std::chrono::milliseconds writer_linger;
  };
  Timing timing{std::chrono::milliseconds(1000), std::chrono::milliseconds(10),
                std::chrono::milliseconds(1000)};
  Timing component_timing{std::chrono::milliseconds(10000), std::chrono::milliseconds(100),
                          std::chrono::milliseconds(10)};
  // The buffer each of Cyclone's receive threads writes incoming datagrams into, in turn, and the
  // chunk it takes at a time. Cyclone's 1 MiB is touched page by page as traffic arrives and given
  // back only when it is full and a new one is taken: an idle daemon's resident memory rose ~4 KB
  // a second for minutes, up to ~2 MiB (two receive threads) before falling back. Control and
  // relayed traffic needs far less. RSCA_DDS_RECEIVE_BUFFER_KIB sets it (at least 4 chunks).
  std::uint32_t receive_buffer_kib = 256;
  static constexpr std::uint32_t kReceiveChunkKib = 64;
  std::string trace = "warning";
  // Cyclone's discovery tag: participants only discover those with the same domain id and tag.
  // Tests and benchmarks give each run one of its own, so runs that happen to share a domain id
  // never meet. Letters, digits, '-' and '_' only.
  std::string tag;

  // Defaults overridden by RSCA_DDS_DOMAIN, RSCA_DDS_INTERFACE, RSCA_DDS_PEER, RSCA_DDS_TRACE,
  // RSCA_DDS_TAG, RSCA_DDS_RECEIVE_BUFFER_KIB, and for `timing` RSCA_DDS_LEASE_MS,
  // RSCA_DDS_HEARTBEAT_MS, RSCA_DDS_WRITER_LINGER_MS (for `component_timing` the same with
  // RSCA_DDS_COMPONENT_ instead of RSCA_DDS_).
  static DdsSettings from_environment();
  // The variables that make a child process join the same domain with the same settings.
  std::vector<std::pair<std::string, std::string>> environment() const;
  // These settings as a component process uses them: its timing is `component_timing`.
  DdsSettings for_component() const;
  // The variables that make a component process join the domain: for_component().environment().
  std::vector<std::pair<std::string, std::string>> component_environment() const;
};

// The Cyclone XML configuration for these settings.
std::string cyclone_config(const DdsSettings &settings);

} // namespace rsca::dds
