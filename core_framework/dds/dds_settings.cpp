#include "dds/dds_settings.hpp"

#include <cctype>
#include <cstdlib>
#include <string_view>

#include <fmt/format.h>

namespace rsca::dds {

// Generated from cyclonedds.xml by cmake/RscaEmbed.cmake.
namespace config {
std::pair<std::string_view, std::string_view> const *embedded_files(std::size_t &count);
}

namespace {

std::string env_or(const char *name, std::string fallback) {
  const char *value = std::getenv(name);
  return value != nullptr && *value != '\0' ? std::string(value) : fallback;
}

std::uint64_t env_number_or(const char *name, std::uint64_t fallback) {
  const char *value = std::getenv(name);
  if (value == nullptr || *value == '\0')
    return fallback;
  char *end = nullptr;
  auto parsed = std::strtoull(value, &end, 10);
  return (end != nullptr && *end == '\0') ? parsed : fallback;
}

void replace_all(std::string &text, std::string_view key, const std::string &value) {
  for (auto at = text.find(key); at != std::string::npos; at = text.find(key, at + value.size()))
    text.replace(at, key.size(), value);
}

} // namespace

DdsSettings DdsSettings::from_environment() {
  DdsSettings s;
  s.domain_id = static_cast<std::uint32_t>(env_number_or("RSCA_DDS_DOMAIN", s.domain_id));
  s.interface_name = env_or("RSCA_DDS_INTERFACE", s.interface_name);
  s.peer = env_or("RSCA_DDS_PEER", s.peer);
  s.lease = std::chrono::milliseconds(
      env_number_or("RSCA_DDS_LEASE_MS", static_cast<std::uint64_t>(s.lease.count())));
  s.component_lease = std::chrono::milliseconds(env_number_or(
      "RSCA_DDS_COMPONENT_LEASE_MS", static_cast<std::uint64_t>(s.component_lease.count())));
  s.trace = env_or("RSCA_DDS_TRACE", s.trace);
  s.tag = env_or("RSCA_DDS_TAG", s.tag);
  // Only characters that need no escaping in the XML configuration.
  std::erase_if(s.tag, [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) == 0 && c != '-' && c != '_';
  });
  std::erase_if(s.peer, [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) == 0 &&
           std::string_view(".:-[]").find(c) == std::string_view::npos;
  });
  return s;
}

std::vector<std::pair<std::string, std::string>> DdsSettings::environment() const {
  return {{"RSCA_DDS_DOMAIN", std::to_string(domain_id)},
          {"RSCA_DDS_INTERFACE", interface_name},
          {"RSCA_DDS_PEER", peer},
          {"RSCA_DDS_LEASE_MS", std::to_string(lease.count())},
          {"RSCA_DDS_COMPONENT_LEASE_MS", std::to_string(component_lease.count())},
          {"RSCA_DDS_TRACE", trace},
          {"RSCA_DDS_TAG", tag}};
}

std::vector<std::pair<std::string, std::string>> DdsSettings::component_environment() const {
  DdsSettings component = *this;
  component.lease = component_lease;
  return component.environment();
}

std::string cyclone_config(const DdsSettings &settings) {
  std::size_t count = 0;
  const auto *files = config::embedded_files(count);
  std::string text(count > 0 ? files[0].second : std::string_view{});
  replace_all(text, "${INTERFACE}", settings.interface_name);
  const bool unicast = !settings.peer.empty();
  // Loopback lacks the MULTICAST flag yet delivers multicast: say so, or Cyclone will not use it.
  replace_all(text, "${MULTICAST}", settings.interface_name == "lo" ? "true" : "default");
  replace_all(text, "${ALLOW_MULTICAST}", unicast ? "false" : "spdp");
  replace_all(text, "${PARTICIPANT_INDEX}", unicast ? "auto" : "none");
  replace_all(text, "${PEERS}",
              unicast ? fmt::format(R"(<Peers><Peer address="{}"/></Peers>)", settings.peer) : "");
  replace_all(text, "${MAX_PARTICIPANTS}", std::to_string(settings.max_participants));
  replace_all(text, "${LEASE}", fmt::format("{}ms", settings.lease.count()));
  replace_all(text, "${TRACE}", settings.trace);
  replace_all(text, "${TAG}", settings.tag);
  return text;
}

} // namespace rsca::dds
