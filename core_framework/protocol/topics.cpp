#include "protocol/topics.hpp"

#include <fmt/format.h>

#include "common/dds_names.hpp"

namespace rsca::protocol {

std::string domain_events_topic(std::string_view domain) {
  return fmt::format("rsca_{}_domain_events", dds_name(domain));
}

std::string connection_topic(std::string_view domain, std::string_view application,
                             const LaunchIdentity &launch, std::string_view connection) {
  return fmt::format("rsca_{}_{}_{}", dds_name(domain),
                     dds_name(fmt::format("{}_{}", application, to_string(launch))),
                     dds_name(connection));
}

std::string runtime_connection_topic(std::string_view domain, std::string_view connection) {
  return fmt::format("rsca_{}_runtime_{}", dds_name(domain), dds_name(connection));
}

std::string channel_topic(std::string_view domain, std::string_view channel) {
  return fmt::format("rsca_{}_channel_{}", dds_name(domain), dds_name(channel));
}

// A prefix of its own beside the domains' rsca_<domain>_ (only a domain named "_tap_" would
// share it), so that a viewer's topic is not a connection's.
std::string tap_topic(std::string_view topic) {
  return fmt::format("rsca__tap__{}", dds_name(topic));
}

} // namespace rsca::protocol
