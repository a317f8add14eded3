// The QoS of a data connection as it travels in component.connect: the SAD's <qos> attributes
// under the same names, every one present, defaults filled in (docs/profiles.md, "Connection QoS
// defaults"), and the DDS QoS a port's writer or reader is created with.
//
//   {"reliability": "reliable", "durability": "volatile", "history": "keeplast", "depth": 16,
//    "deadline_ns": "infinite", "latencybudget_ns": 0, "transportpriority": 0,
//    "liveliness": "automatic", "lease_ns": "infinite", "ownership": "shared", "strength": 0}
//
// Durations are whole nanoseconds or the string "infinite". "depth" is present with keeplast
// only.
#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "common/diagnostic.hpp"
#include "dds/entity.hpp"
#include "profile/assembly.hpp"

namespace rsca::dds {

// Defaults of the fields a SAD leaves out.
inline constexpr std::uint32_t kDefaultDepth = 16;

nlohmann::json qos_to_json(const profile::ConnectionQos &qos);

// The connection QoS `json` describes, every field set (absent keys take the defaults). Keys are
// the SAD's <qos> attributes with their values as the SAD gives them ("deadline": "100ms",
// "depth": 4 or "4"; one parser, profile/connection_qos.hpp), or the durations in whole
// nanoseconds as above ("deadline_ns"). Unknown keys and bad values are errors naming the key and
// quoting at most an excerpt of the value.
Expected<profile::ConnectionQos> connection_qos_from_json(const nlohmann::json &json);

// Why a writer with QoS `offered` and a reader with QoS `requested` would never match under
// DDS's requested/offered rules (reliability, durability, deadline, latency budget, liveliness,
// ownership), or nothing when they match. Absent fields take the defaults.
std::optional<std::string> qos_incompatibility(const profile::ConnectionQos &offered,
                                               const profile::ConnectionQos &requested);

// A QoS for a port's writer or reader. Absent keys take the defaults; unknown keys, values of the
// wrong type and values out of range are errors naming the key.
Expected<Qos> qos_from_json(const nlohmann::json &json);

} // namespace rsca::dds
