// Private to the component runtime: the fields a provides port's content filter
// (common/content_filter.hpp) sees in each port type's value, by name.
#pragma once

#include <optional>
#include <string_view>

#include "common/content_filter.hpp"
#include "component/port_types.hpp"

namespace rsca::component::detail {

std::optional<FilterValue> field_of(const port::PropertyEvent &e, std::string_view field);
std::optional<FilterValue> field_of(const port::Command &c, std::string_view field);
std::optional<FilterValue> field_of(const port::Samples &s, std::string_view field);

} // namespace rsca::component::detail
