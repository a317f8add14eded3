// A PRF's property definitions and an SCD's component description as JSON, and back: all they
// hold, values as their profile text read back with their declared type. Runtime models
// (profile/runtime_model.hpp) are made of them.
#pragma once

#include <string>

#include <nlohmann/json.hpp>
#include <tl/expected.hpp>

#include "profile/prf.hpp"
#include "profile/scd.hpp"

namespace rsca::profile {

nlohmann::json to_json(const Properties &prf);
// The error says what does not read back, e.g. a value that does not fit its declared type.
tl::expected<Properties, std::string> properties_from_json(const nlohmann::json &json);

nlohmann::json to_json(const SoftwareComponent &scd);
tl::expected<SoftwareComponent, std::string>
software_component_from_json(const nlohmann::json &json);

} // namespace rsca::profile
