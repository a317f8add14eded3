// Property values as JSON, the encoding of the control plane (docs/architecture.md): numbers,
// booleans and strings as themselves; complex and utctime values as their profile text;
// sequences as arrays; structs as objects keyed by member id; struct sequences as arrays of
// objects. Non-finite floating values, which JSON cannot hold, travel as "nan", "inf", "-inf".
#pragma once

#include <string>

#include <nlohmann/json.hpp>
#include <tl/expected.hpp>

#include "profile/prf.hpp"

namespace rsca::profile {

nlohmann::json to_json(const Scalar &value);
nlohmann::json to_json(const PropertyValue &value);

// The value `json` gives for `definition`, checked as a configure must check it: the JSON type
// must fit the declared type, numbers must be within the type and the PRF range, a simple with
// enumerations takes one of their values or labels, and struct members must exist. A struct
// value holds only the members `json` names (a configure updates those). The error names the
// property (and member), e.g. `property "rate_hz": 1e9 is outside its range 0.1..10000`.
tl::expected<PropertyValue, std::string> from_json(const PropertyDefinition &definition,
                                                   const nlohmann::json &json);

} // namespace rsca::profile
