#include "component/filter_fields.hpp"

#include <nlohmann/json.hpp>

#include "protocol/json_text.hpp"

namespace rsca::component::detail {

namespace {

std::optional<FilterValue> json_field(const nlohmann::json &value) {
  if (value.is_number())
    return value.get<double>();
  if (value.is_string())
    return value.get<std::string>();
  if (value.is_boolean())
    return value.get<bool>();
  return std::nullopt;
}

// A member path ("a.b") inside a JSON value.
std::optional<FilterValue> json_path(const nlohmann::json &value, std::string_view path) {
  const nlohmann::json *at = &value;
  while (!path.empty()) {
    const auto dot = path.find('.');
    const std::string name(path.substr(0, dot));
    if (!at->is_object() || !at->contains(name))
      return std::nullopt;
    at = &at->at(name);
    path = dot == std::string_view::npos ? std::string_view() : path.substr(dot + 1);
  }
  return json_field(*at);
}

} // namespace

// id, source, timestamp_ns, value (and value.member); any other name is the event's value when
// the event bears that id ("range < 10" on an event {id: range, value: 5}), else a member of it.
std::optional<FilterValue> field_of(const port::PropertyEvent &e, std::string_view field) {
  if (field == "id")
    return e.id;
  if (field == "source")
    return e.source;
  if (field == "timestamp_ns")
    return static_cast<double>(e.timestamp_ns);
  const auto value =
      protocol::parse_json(e.value).value_or(nlohmann::json(nlohmann::json::value_t::discarded));
  if (value.is_discarded())
    return std::nullopt;
  if (field == "value" || field == e.id)
    return json_field(value);
  if (field.starts_with("value."))
    return json_path(value, field.substr(6));
  return json_path(value, field);
}

std::optional<FilterValue> field_of(const port::Command &c, std::string_view field) {
  if (field == "name")
    return c.name;
  if (field == "source")
    return c.source;
  if (field == "text")
    return c.text;
  if (field == "timestamp_ns")
    return static_cast<double>(c.timestamp_ns);
  return std::nullopt;
}

std::optional<FilterValue> field_of(const port::Samples &s, std::string_view field) {
  if (field == "stream_id")
    return s.stream_id;
  if (field == "sample_rate")
    return s.sample_rate;
  if (field == "complex")
    return s.complex;
  if (field == "end_of_stream")
    return s.end_of_stream;
  if (field == "timestamp_ns")
    return static_cast<double>(s.timestamp_ns);
  return std::nullopt;
}

} // namespace rsca::component::detail
