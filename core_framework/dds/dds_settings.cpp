#include "dds/dds_settings.hpp"
#include "common/text.hpp"

#include <algorithm>

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

} // namespace

namespace {

std::chrono::milliseconds env_ms_or(const std::string &name, std::chrono::milliseconds fallback) {
  return std::chrono::milliseconds(
      env_number_or(name.c_str(), static_cast<std::uint64_t>(fallback.count())));
}

// The timing's variables: RSCA_DDS_LEASE_MS... with prefix "RSCA_DDS_".
std::vector<std::pair<std::string, std::string>> timing_environment(const DdsSettings::Timing &t,
                                                                    const std::string &prefix) {
  return {{prefix + "LEASE_MS", std::to_string(t.lease.count())},
          {prefix + "HEARTBEAT_MS", std::to_string(t.heartbeat.count())},
          {prefix + "WRITER_LINGER_MS", std::to_string(t.writer_linger.count())}};
}

DdsSettings::Timing timing_from_environment(DdsSettings::Timing t, const std::string &prefix) {
  t.lease = env_ms_or(prefix + "LEASE_MS", t.lease);
  t.heartbeat = env_ms_or(prefix + "HEARTBEAT_MS", t.heartbeat);
  t.writer_linger = env_ms_or(prefix + "WRITER_LINGER_MS", t.writer_linger);
  return t;
}

constexpr const char *kPrefix = "RSCA_DDS_";
constexpr const char *kComponentPrefix = "RSCA_DDS_COMPONENT_";

} // namespace

DdsSettings DdsSettings::from_environment() {
  DdsSettings s;
  s.domain_id = static_cast<std::uint32_t>(env_number_or("RSCA_DDS_DOMAIN", s.domain_id));
  s.interface_name = env_or("RSCA_DDS_INTERFACE", s.interface_name);
  s.peer = env_or("RSCA_DDS_PEER", s.peer);
  s.timing = timing_from_environment(s.timing, kPrefix);
  s.component_timing = timing_from_environment(s.component_timing, kComponentPrefix);
  s.trace = env_or("RSCA_DDS_TRACE", s.trace);
  s.receive_buffer_kib = std::max<std::uint32_t>(
      4 * kReceiveChunkKib,
      static_cast<std::uint32_t>(std::min<std::uint64_t>(
          env_number_or("RSCA_DDS_RECEIVE_BUFFER_KIB", s.receive_buffer_kib), 1U << 20)));
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
  std::vector<std::pair<std::string, std::string>> env{
      {"RSCA_DDS_DOMAIN", std::to_string(domain_id)},
      {"RSCA_DDS_INTERFACE", interface_name},
      {"RSCA_DDS_PEER", peer},
      {"RSCA_DDS_TRACE", trace},
      {"RSCA_DDS_TAG", tag},
      {"RSCA_DDS_RECEIVE_BUFFER_KIB", std::to_string(receive_buffer_kib)}};
  for (auto &variable : timing_environment(timing, kPrefix))
    env.push_back(std::move(variable));
  for (auto &variable : timing_environment(component_timing, kComponentPrefix))
    env.push_back(std::move(variable));
  return env;
}

DdsSettings DdsSettings::for_component() const {
  DdsSettings component = *this;
  component.timing = component_timing;
  return component;
}

std::vector<std::pair<std::string, std::string>> DdsSettings::component_environment() const {
  return for_component().environment();
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
  replace_all(text, "${LEASE}", fmt::format("{}ms", settings.timing.lease.count()));
  replace_all(text, "${HEARTBEAT}", fmt::format("{}ms", settings.timing.heartbeat.count()));
  replace_all(text, "${WRITER_LINGER}", fmt::format("{}ms", settings.timing.writer_linger.count()));
  replace_all(text, "${RECEIVE_BUFFER}", fmt::format("{}KiB", settings.receive_buffer_kib));
  replace_all(text, "${RECEIVE_CHUNK}", fmt::format("{}KiB", DdsSettings::kReceiveChunkKib));
  replace_all(text, "${TRACE}", settings.trace);
  replace_all(text, "${TAG}", settings.tag);
  return text;
}

} // namespace rsca::dds
