#include "profile/property_json.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <type_traits>

#include <fmt/format.h>

namespace rsca::profile {
namespace {

using Json = nlohmann::json;
template <typename T>
using Result = tl::expected<T, std::string>;

tl::unexpected<std::string> failure(std::string message) {
  return tl::unexpected(std::move(message));
}

// A JSON value as it appears in messages, cut short when long.
std::string shown(const Json &json) {
  constexpr std::size_t kMax = 40;
  std::string text = json.dump();
  if (text.size() > kMax)
    text = text.substr(0, kMax - 3) + "...";
  return text;
}

std::string type_label(TypeSpec spec) {
  const std::string base(to_string(spec.type));
  return spec.complex ? "complex " + base : base;
}

tl::unexpected<std::string> wrong_type(const Json &json, TypeSpec spec) {
  return failure(fmt::format("{} is not a {}", shown(json), type_label(spec)));
}

// Floats travel as the shortest text that reads back as the same float, not as the double
// nearest to the float (0.1f is 0.1, not 0.10000000149011612).
Json float_json(float value) {
  std::array<char, 64> buffer{};
  const auto [end, ec] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  double wide = value;
  if (ec == std::errc{})
    std::from_chars(buffer.data(), end, wide);
  return wide;
}

struct ScalarToJson {
  Json operator()(bool value) const { return value; }
  Json operator()(char value) const { return std::string(1, value); }
  Json operator()(const std::string &value) const { return value; }
  Json operator()(const UtcTime &value) const { return format_scalar(value); }
  Json operator()(const std::complex<double> &value) const { return format_scalar(value); }
  Json operator()(float value) const {
    return std::isfinite(value) ? float_json(value) : Json(format_scalar(value));
  }
  Json operator()(double value) const {
    return std::isfinite(value) ? Json(value) : Json(format_scalar(value));
  }
  template <typename T>
  Json operator()(T value) const {
    return value;
  }
};

Json struct_json(const StructValue &value) {
  Json object = Json::object();
  for (const auto &[id, member] : value.members)
    object[id] = std::visit([](const auto &m) { return to_json(PropertyValue(m)); }, member);
  return object;
}

// --------------------------------------------------------------------------------------------
// From JSON to one scalar of a declared type

template <typename T>
Result<Scalar> integer_as(TypeSpec spec, const Json &original, const Json &json) {
  constexpr T kMin = std::numeric_limits<T>::min();
  constexpr T kMax = std::numeric_limits<T>::max();
  bool fits = false;
  if (json.is_number_unsigned()) {
    fits = json.get<std::uint64_t>() <= std::uint64_t{kMax};
  } else {
    const auto v = json.get<std::int64_t>();
    fits =
        v >= std::int64_t{kMin} && (v < 0 || static_cast<std::uint64_t>(v) <= std::uint64_t{kMax});
  }
  if (!fits)
    return failure(fmt::format("{} is out of range for {} ({}..{})", shown(original),
                               type_label(spec), +kMin, +kMax));
  return Scalar(std::in_place_type<T>, json.get<T>());
}

// An integral JSON number as a JSON integer (5.0 is the integer 5; 2.5 is not an integer).
std::optional<Json> as_integer(const Json &json) {
  if (json.is_number_integer())
    return json;
  if (!json.is_number_float())
    return std::nullopt;
  const double value = json.get<double>();
  if (!std::isfinite(value) || std::trunc(value) != value)
    return std::nullopt;
  if (value >= 0 && value < 0x1p64)
    return Json(static_cast<std::uint64_t>(value));
  if (value < 0 && value >= -0x1p63)
    return Json(static_cast<std::int64_t>(value));
  return Json(value < 0 ? std::numeric_limits<std::int64_t>::min()
                        : std::numeric_limits<std::int64_t>::max()); // out of every range
}

Result<Scalar> integer_from_json(TypeSpec spec, const Json &json) {
  const auto integer = as_integer(json);
  if (!integer)
    return wrong_type(json, spec);
  switch (spec.type) {
  case SimpleType::Octet:
    return integer_as<std::uint8_t>(spec, json, *integer);
  case SimpleType::Short:
    return integer_as<std::int16_t>(spec, json, *integer);
  case SimpleType::UShort:
    return integer_as<std::uint16_t>(spec, json, *integer);
  case SimpleType::Long:
    return integer_as<std::int32_t>(spec, json, *integer);
  case SimpleType::ULong:
    return integer_as<std::uint32_t>(spec, json, *integer);
  case SimpleType::LongLong:
    return integer_as<std::int64_t>(spec, json, *integer);
  case SimpleType::ULongLong:
    return integer_as<std::uint64_t>(spec, json, *integer);
  default:
    return wrong_type(json, spec);
  }
}

Result<Scalar> floating_from_json(TypeSpec spec, const Json &json) {
  if (json.is_string()) {
    // Only the values JSON has no number for: "nan", "inf", "-inf".
    auto value = parse_scalar(spec, json.get<std::string>());
    const bool non_finite = value && std::visit(
                                         [](const auto &v) {
                                           using T = std::decay_t<decltype(v)>;
                                           if constexpr (std::is_floating_point_v<T>)
                                             return !std::isfinite(v);
                                           return false;
                                         },
                                         *value);
    if (!non_finite)
      return wrong_type(json, spec);
    return value;
  }
  if (!json.is_number())
    return wrong_type(json, spec);
  const double value = json.get<double>();
  if (spec.type == SimpleType::Double)
    return Scalar(value);
  if (std::fabs(value) > std::numeric_limits<float>::max())
    return failure(fmt::format("{} is out of range for float", shown(json)));
  return Scalar(static_cast<float>(value));
}

// The JSON type and the declared type agree, and the value fits the type.
Result<Scalar> typed_scalar(TypeSpec spec, const Json &json) {
  if (spec.complex) {
    if (!json.is_string())
      return wrong_type(json, spec);
    return parse_scalar(spec, json.get<std::string>());
  }
  switch (spec.type) {
  case SimpleType::Boolean:
    if (!json.is_boolean())
      return wrong_type(json, spec);
    return Scalar(json.get<bool>());
  case SimpleType::Char:
    if (!json.is_string() || json.get_ref<const std::string &>().size() != 1)
      return wrong_type(json, spec);
    return Scalar(json.get_ref<const std::string &>().front());
  case SimpleType::Float:
  case SimpleType::Double:
    return floating_from_json(spec, json);
  case SimpleType::String:
  case SimpleType::ObjRef:
  case SimpleType::UtcTime:
    if (!json.is_string())
      return wrong_type(json, spec);
    return parse_scalar(spec, json.get<std::string>());
  default:
    return integer_from_json(spec, json);
  }
}

struct ScalarRules {
  TypeSpec type;
  const std::optional<ValueRange> &range;
  const std::vector<Enumeration> &enumerations;
};

std::string enumeration_list(const std::vector<Enumeration> &enumerations) {
  std::string list;
  for (const auto &e : enumerations)
    list += (list.empty() ? "" : ", ") + fmt::format("{} ({})", e.label, format_scalar(e.value));
  return list;
}

Result<Scalar> check_enumeration(const std::vector<Enumeration> &enumerations, const Json &json,
                                 Scalar value) {
  if (enumerations.empty())
    return value;
  for (const auto &e : enumerations)
    if (e.value == value)
      return value;
  return failure(fmt::format("{} is none of its enumerations: {}", shown(json),
                             enumeration_list(enumerations)));
}

Result<Scalar> check_range(const std::optional<ValueRange> &range, const Json &json, Scalar value) {
  if (!range)
    return value;
  const bool inside = satisfies(Action::Ge, value, range->min).value_or(true) &&
                      satisfies(Action::Le, value, range->max).value_or(true);
  if (inside)
    return value;
  return failure(fmt::format("{} is outside its range {}..{}", shown(json),
                             format_scalar(range->min), format_scalar(range->max)));
}

Result<Scalar> scalar_from_json(const ScalarRules &rules, const Json &json) {
  // A value may name an enumeration by its label.
  if (json.is_string())
    for (const auto &e : rules.enumerations)
      if (e.label == json.get_ref<const std::string &>())
        return e.value;
  return typed_scalar(rules.type, json)
      .and_then([&](Scalar v) { return check_enumeration(rules.enumerations, json, std::move(v)); })
      .and_then([&](Scalar v) { return check_range(rules.range, json, std::move(v)); });
}

// --------------------------------------------------------------------------------------------
// Forms

Result<std::vector<Scalar>> sequence_from_json(const ScalarRules &rules, const Json &json) {
  if (!json.is_array())
    return failure(fmt::format("{} is not an array of {}", shown(json), type_label(rules.type)));
  std::vector<Scalar> values;
  values.reserve(json.size());
  for (std::size_t i = 0; i < json.size(); ++i) {
    auto value = scalar_from_json(rules, json[i]);
    if (!value)
      return failure(fmt::format("element {}: {}", i, value.error()));
    values.push_back(std::move(*value));
  }
  return values;
}

Result<MemberValue> member_from_json(const StructMember &member, const Json &json) {
  if (const auto *simple = std::get_if<SimpleProperty>(&member))
    return scalar_from_json({simple->type, simple->range, simple->enumerations}, json)
        .map([](Scalar v) { return MemberValue(std::move(v)); });
  const auto &sequence = std::get<SimpleSequenceProperty>(member);
  static const std::vector<Enumeration> kNone;
  return sequence_from_json({sequence.type, sequence.range, kNone}, json)
      .map([](std::vector<Scalar> v) { return MemberValue(std::move(v)); });
}

Result<StructValue> struct_from_json(const StructProperty &definition, const Json &json) {
  if (!json.is_object())
    return failure(fmt::format("{} is not an object of struct members", shown(json)));
  StructValue value;
  for (const auto &[member_id, member_json] : json.items()) {
    const StructMember *member = definition.find_member(member_id);
    if (member == nullptr)
      return failure(fmt::format("struct \"{}\" has no member \"{}\"", definition.id, member_id));
    auto member_value = member_from_json(*member, member_json);
    if (!member_value)
      return failure(fmt::format("member \"{}\": {}", member_id, member_value.error()));
    value.members.emplace_back(member_id, std::move(*member_value));
  }
  return value;
}

Result<std::vector<StructValue>> struct_sequence_from_json(const StructSequenceProperty &definition,
                                                           const Json &json) {
  if (!json.is_array())
    return failure(fmt::format("{} is not an array of structs", shown(json)));
  std::vector<StructValue> values;
  values.reserve(json.size());
  for (std::size_t i = 0; i < json.size(); ++i) {
    auto value = struct_from_json(definition.element, json[i]);
    if (!value)
      return failure(fmt::format("element {}: {}", i, value.error()));
    values.push_back(std::move(*value));
  }
  return values;
}

template <typename T>
Result<PropertyValue> widen(Result<T> value) {
  return std::move(value).map([](T v) { return PropertyValue(std::move(v)); });
}

Result<PropertyValue> value_from_json(const PropertyDefinition &definition, const Json &json) {
  static const std::vector<Enumeration> kNone;
  if (const auto *d = std::get_if<SimpleProperty>(&definition))
    return widen(scalar_from_json({d->type, d->range, d->enumerations}, json));
  if (const auto *d = std::get_if<SimpleSequenceProperty>(&definition))
    return widen(sequence_from_json({d->type, d->range, kNone}, json));
  if (const auto *d = std::get_if<StructProperty>(&definition))
    return widen(struct_from_json(*d, json));
  return widen(struct_sequence_from_json(std::get<StructSequenceProperty>(definition), json));
}

} // namespace

Json to_json(const Scalar &value) {
  return std::visit(ScalarToJson{}, value);
}

Json to_json(const PropertyValue &value) {
  if (const auto *scalar = std::get_if<Scalar>(&value))
    return to_json(*scalar);
  if (const auto *sequence = std::get_if<std::vector<Scalar>>(&value)) {
    Json array = Json::array();
    for (const auto &v : *sequence)
      array.push_back(to_json(v));
    return array;
  }
  if (const auto *structure = std::get_if<StructValue>(&value))
    return struct_json(*structure);
  Json array = Json::array();
  for (const auto &v : std::get<std::vector<StructValue>>(value))
    array.push_back(struct_json(v));
  return array;
}

tl::expected<PropertyValue, std::string> from_json(const PropertyDefinition &definition,
                                                   const nlohmann::json &json) {
  auto value = value_from_json(definition, json);
  if (!value)
    return failure(fmt::format("property \"{}\": {}", common_of(definition).id, value.error()));
  return value;
}

} // namespace rsca::profile
