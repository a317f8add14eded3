// The one parser of a connection's QoS values: each attribute of a SAD connection's <qos> (rsca
// extension, docs/profiles.md) from its text. The SAD reader reads <qos> with it, and the domain
// reads the QoS of `rsca connect --qos` with it (dds::connection_qos_from_json), so that both
// take the same names and values ("reliability=besteffort", "depth=4", "deadline=100ms").
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>

#include <tl/expected.hpp>

#include "profile/assembly.hpp"

namespace rsca::profile {

// The attribute names, in the schema's order.
inline constexpr std::array<std::string_view, 12> kQosAttributes{
    "reliability",       "durability", "history", "depth",     "deadline", "latencybudget",
    "transportpriority", "liveliness", "lease",   "ownership", "strength", "transport"};

bool is_qos_attribute(std::string_view name);

// Sets the field of `qos` that attribute `name` names from its `text`. An error says what is
// wrong with the value, to follow `is "<text>", ` ("not one of besteffort, reliable"); it
// never quotes the text.
tl::expected<void, std::string> set_qos_attribute(ConnectionQos &qos, std::string_view name,
                                                  std::string_view text);

// Values that make no sense together whatever they are: a depth with keepall, a strength
// without exclusive ownership.
std::optional<std::string> qos_inconsistency(const ConnectionQos &qos);

// What a transport delivers of the QoS a connection can ask for: the one table that both the
// check of a transport named (SAD, rsca connect) and the choice of one not named read. Direct DDS
// honours all that DDS does; the nodes' rings and relays, and a TCP stream, what is listed.
struct TransportHonours {
  Durability durability;    // the most durable it keeps for a late joiner
  bool exclusive_ownership; // delivers the strongest live writer only
  bool reliable_keep_all;   // a reliable keep-all writer waits for, or reports, a slow reader
  bool liveliness_lease;    // tells a writer that stopped asserting itself within a lease
};
TransportHonours honours(Transport transport);

// Why `transport` cannot carry a connection of `qos` (absent fields taken as their defaults),
// or nothing when it honours every policy asked for.
std::optional<std::string> not_honoured(const ConnectionQos &qos, Transport transport);

// The transport of a connection that names none: the nodes' when they honour its QoS, else
// direct DDS.
Transport transport_for(const ConnectionQos &qos);

} // namespace rsca::profile
