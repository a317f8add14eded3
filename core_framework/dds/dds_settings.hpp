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
  std::string peer = "127.0.0.1";
  std::uint32_t max_participants = 600;
  std::chrono::milliseconds lease{1000};
  std::string trace = "warning";
  // Cyclone's discovery tag: participants only discover those with the same domain id and tag.
  // Tests and benchmarks give each run one of its own, so runs that happen to share a domain id
  // never meet. Letters, digits, '-' and '_' only.
  std::string tag;

  // Defaults overridden by RSCA_DDS_DOMAIN, RSCA_DDS_INTERFACE, RSCA_DDS_PEER, RSCA_DDS_LEASE_MS,
  // RSCA_DDS_TRACE, RSCA_DDS_TAG.
  static DdsSettings from_environment();
  // The variables that make a child process join the same domain.
  std::vector<std::pair<std::string, std::string>> environment() const;
};

// The Cyclone XML configuration for these settings.
std::string cyclone_config(const DdsSettings &settings);

} // namespace rsca::dds
