// The project's Cyclone configuration as DdsSettings fill it in.
#include <cstdlib>
#include <regex>

#include <catch2/catch.hpp>

#include "dds/dds_settings.hpp"

using rsca::dds::cyclone_config;
using rsca::dds::DdsSettings;

namespace {

bool contains(const std::string &text, const std::string &part) {
  return text.find(part) != std::string::npos;
}

std::string value_of(const std::vector<std::pair<std::string, std::string>> &env,
                     const std::string &name) {
  for (const auto &[key, value] : env)
    if (key == name)
      return value;
  return {};
}

} // namespace

TEST_CASE("discovery is by multicast, declared on loopback, unless a peer is given", "[dds]") {
  DdsSettings settings;
  const auto multicast = cyclone_config(settings);
  CHECK(contains(multicast, R"(<NetworkInterface name="lo" multicast="true"/>)"));
  CHECK(contains(multicast, "<AllowMulticast>spdp</AllowMulticast>"));
  CHECK(contains(multicast, "<ParticipantIndex>none</ParticipantIndex>"));
  CHECK_FALSE(contains(multicast, "<Peers>"));

  settings.peer = "10.0.0.7";
  settings.interface_name = "eth0";
  const auto unicast = cyclone_config(settings);
  CHECK(contains(unicast, R"(<NetworkInterface name="eth0" multicast="default"/>)"));
  CHECK(contains(unicast, "<AllowMulticast>false</AllowMulticast>"));
  CHECK(contains(unicast, "<ParticipantIndex>auto</ParticipantIndex>"));
  CHECK(contains(unicast, R"(<Peers><Peer address="10.0.0.7"/></Peers>)"));
  // Every placeholder is filled in (the file's own comment speaks of "${...}").
  CHECK_FALSE(std::regex_search(unicast, std::regex(R"(\$\{[A-Z_]+\})")));
  CHECK_FALSE(std::regex_search(multicast, std::regex(R"(\$\{[A-Z_]+\})")));
}

TEST_CASE("a peer from the environment cannot break the configuration's XML", "[dds]") {
  ::setenv("RSCA_DDS_PEER", R"(127.0.0.1"/><x a=")", 1);
  const auto settings = DdsSettings::from_environment();
  ::unsetenv("RSCA_DDS_PEER");
  CHECK(settings.peer == "127.0.0.1xa");
}

TEST_CASE("component processes get the component lease, the rest of the settings alike", "[dds]") {
  DdsSettings settings;
  settings.lease = std::chrono::milliseconds(1000);
  settings.component_lease = std::chrono::milliseconds(7000);
  settings.tag = "t1";
  const auto own = settings.environment();
  const auto component = settings.component_environment();
  CHECK(value_of(own, "RSCA_DDS_LEASE_MS") == "1000");
  CHECK(value_of(component, "RSCA_DDS_LEASE_MS") == "7000");
  CHECK(value_of(component, "RSCA_DDS_COMPONENT_LEASE_MS") == "7000");
  CHECK(value_of(component, "RSCA_DDS_TAG") == "t1");
}
