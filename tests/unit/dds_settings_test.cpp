// The project's Cyclone configuration as DdsSettings fill it in.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdlib>
#include <regex>

#include <catch2/catch.hpp>

#include "dds/dds_settings.hpp"
#include "dds/participant.hpp"
#include "test_domain.hpp"

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

TEST_CASE("component processes get the component timing, the rest of the settings alike", "[dds]") {
  using std::chrono::milliseconds;
  DdsSettings settings;
  settings.timing = {milliseconds(1000), milliseconds(10), milliseconds(900)};
  settings.component_timing = {milliseconds(7000), milliseconds(70), milliseconds(7)};
  settings.tag = "t1";
  const auto own = settings.environment();
  const auto component = settings.component_environment();
  CHECK(value_of(own, "RSCA_DDS_LEASE_MS") == "1000");
  CHECK(value_of(own, "RSCA_DDS_HEARTBEAT_MS") == "10");
  CHECK(value_of(own, "RSCA_DDS_WRITER_LINGER_MS") == "900");
  CHECK(value_of(component, "RSCA_DDS_LEASE_MS") == "7000");
  CHECK(value_of(component, "RSCA_DDS_HEARTBEAT_MS") == "70");
  CHECK(value_of(component, "RSCA_DDS_WRITER_LINGER_MS") == "7");
  CHECK(value_of(component, "RSCA_DDS_COMPONENT_LEASE_MS") == "7000");
  CHECK(value_of(component, "RSCA_DDS_TAG") == "t1");

  const auto daemon_config = cyclone_config(settings);
  const auto component_config = cyclone_config(settings.for_component());
  CHECK(contains(daemon_config, "<LeaseDuration>1000ms</LeaseDuration>"));
  CHECK(contains(daemon_config, ">10ms</HeartbeatInterval>"));
  CHECK(contains(daemon_config, "<WriterLingerDuration>900ms</WriterLingerDuration>"));
  CHECK(contains(component_config, "<LeaseDuration>7000ms</LeaseDuration>"));
  CHECK(contains(component_config, ">70ms</HeartbeatInterval>"));
  CHECK(contains(component_config, "<WriterLingerDuration>7ms</WriterLingerDuration>"));
}

TEST_CASE("both timings come from the environment, and a child process keeps them", "[dds]") {
  const std::vector<std::pair<const char *, const char *>> variables{
      {"RSCA_DDS_HEARTBEAT_MS", "20"},
      {"RSCA_DDS_WRITER_LINGER_MS", "30"},
      {"RSCA_DDS_COMPONENT_LEASE_MS", "4000"},
      {"RSCA_DDS_COMPONENT_HEARTBEAT_MS", "200"},
      {"RSCA_DDS_COMPONENT_WRITER_LINGER_MS", "40"}};
  for (const auto &[name, value] : variables)
    ::setenv(name, value, 1);
  const auto settings = DdsSettings::from_environment();
  for (const auto &[name, value] : variables)
    ::unsetenv(name);
  CHECK(settings.timing.heartbeat == std::chrono::milliseconds(20));
  CHECK(settings.timing.writer_linger == std::chrono::milliseconds(30));
  CHECK(settings.component_timing.lease == std::chrono::milliseconds(4000));
  CHECK(settings.component_timing.heartbeat == std::chrono::milliseconds(200));
  CHECK(settings.component_timing.writer_linger == std::chrono::milliseconds(40));
  // What a node hands a component, read back there, is the component timing.
  const auto env = settings.component_environment();
  for (const auto &[name, value] : env)
    ::setenv(name.c_str(), value.c_str(), 1);
  const auto in_component = DdsSettings::from_environment();
  for (const auto &[name, value] : env)
    ::unsetenv(name.c_str());
  CHECK(in_component.timing.lease == std::chrono::milliseconds(4000));
  CHECK(in_component.timing.heartbeat == std::chrono::milliseconds(200));
  CHECK(in_component.timing.writer_linger == std::chrono::milliseconds(40));
}

TEST_CASE("a domain id whose discovery port does not exist is refused with the reason", "[dds]") {
  auto settings = rsca::test::isolated_settings();
  settings.domain_id = 240; // 7400 + 250 x 240 = 67400
  auto participant = rsca::dds::Participant::create(settings);
  REQUIRE_FALSE(participant.has_value());
  CHECK_THAT(participant.error().to_string(),
             Catch::Contains("creating DDS domain 240 (its discovery port would be 67400, past "
                             "65535; domain ids 0-101 work)"));
}

TEST_CASE("a domain whose discovery port another socket holds is refused with the likely reason",
          "[dds]") {
  // What failed a CI run: another process's socket held the port first (here, this test's).
  int holder = ::socket(AF_INET, SOCK_DGRAM, 0);
  REQUIRE(holder >= 0);
  std::uint32_t domain_id = 0;
  for (std::uint32_t id = 102; id <= 214 && domain_id == 0; ++id) {
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<std::uint16_t>(7400 + 250 * id));
    address.sin_addr.s_addr = htonl(INADDR_ANY);
    if (::bind(holder, reinterpret_cast<sockaddr *>(&address), sizeof address) == 0)
      domain_id = id;
  }
  REQUIRE(domain_id != 0);
  auto settings = rsca::test::isolated_settings();
  settings.domain_id = domain_id;
  auto participant = rsca::dds::Participant::create(settings);
  ::close(holder);
  REQUIRE_FALSE(participant.has_value());
  CHECK_THAT(participant.error().to_string(),
             Catch::Contains("is among the ephemeral ports another socket may hold"));
}

TEST_CASE("the receive buffer is 256 KiB unless the environment says, at least four chunks",
          "[dds]") {
  DdsSettings settings;
  CHECK_THAT(cyclone_config(settings),
             Catch::Contains("<ReceiveBufferSize>256KiB</ReceiveBufferSize>") &&
                 Catch::Contains("<ReceiveBufferChunkSize>64KiB</ReceiveBufferChunkSize>"));
  ::setenv("RSCA_DDS_RECEIVE_BUFFER_KIB", "1024", 1);
  const auto larger = DdsSettings::from_environment();
  ::setenv("RSCA_DDS_RECEIVE_BUFFER_KIB", "8", 1);
  const auto too_small = DdsSettings::from_environment();
  ::unsetenv("RSCA_DDS_RECEIVE_BUFFER_KIB");
  CHECK(larger.receive_buffer_kib == 1024);
  CHECK(too_small.receive_buffer_kib == 4 * DdsSettings::kReceiveChunkKib);
  // A child process gets the same.
  bool passed_on = false;
  for (const auto &[name, value] : larger.environment())
    passed_on = passed_on || (name == "RSCA_DDS_RECEIVE_BUFFER_KIB" && value == "1024");
  CHECK(passed_on);
  // And Cyclone takes it: a participant is made with it.
  auto own = larger;
  own.domain_id = rsca::test::isolated_domain_id();
  own.tag = rsca::test::isolated_tag();
  auto participant = rsca::dds::Participant::create(own);
  CHECK(participant.has_value());
}
