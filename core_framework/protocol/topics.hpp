// The DDS topic names of rsca, made here only. Names from profiles and users go through
// dds_name (common/dds_names.hpp), so that none makes an invalid or ambiguous topic name.
#pragma once

#include <string>
#include <string_view>

#include "protocol/addresses.hpp"

namespace rsca::protocol {

// The control plane's three topics, shared by every domain (partitions keep domains apart).
inline constexpr const char *kRequestTopic = "rsca_ctl_Request";
inline constexpr const char *kReplyTopic = "rsca_ctl_Reply";
// Version 2: keyed by announcer and slot (dds/control.idl). A daemon of the address-keyed version
// is on another topic, never mis-reading these.
inline constexpr const char *kAnnouncementTopic = "rsca_ctl_Announcement_v2";
// The kind of an announcement's last sample when its announcer withdrew it (it stopped), unlike
// one lost with the announcer's DDS lease (it died, or is cut off).
inline constexpr const char *kWithdrawnKind = "withdrawn";

// A domain's events (control/domain_events.hpp).
std::string domain_events_topic(std::string_view domain);
// A connection of a SAD, in one launch of its application.
std::string connection_topic(std::string_view domain, std::string_view application,
                             const LaunchIdentity &launch, std::string_view connection);
// A connection made at run time (rsca connect).
std::string runtime_connection_topic(std::string_view domain, std::string_view connection);
// An event channel.
std::string channel_topic(std::string_view domain, std::string_view channel);
// A node's lossy copy of the records of `topic` for a viewer (rsca echo, rsca hz).
std::string tap_topic(std::string_view topic);

} // namespace rsca::protocol
