#include "component/properties.hpp"

#include <algorithm>
#include <array>

#include <fmt/format.h>

#include "profile/code_description.hpp"
#include "profile/property_json.hpp"

namespace rsca::component {
namespace detail {
namespace {

using profile::Scalar;
using profile::SimpleType;
using profile::TypeSpec;

template <typename T>
std::size_t index_of() {
  return Scalar(std::in_place_type<T>).index();
}

// The Scalar alternative parse_scalar gives for a declared type.
std::size_t scalar_index(TypeSpec spec) {
  if (spec.complex)
    return index_of<std::complex<double>>();
  switch (spec.type) {
  case SimpleType::Boolean:
    return index_of<bool>();
  case SimpleType::Char:
    return index_of<char>();
  case SimpleType::Octet:
    return index_of<std::uint8_t>();
  case SimpleType::Short:
    return index_of<std::int16_t>();
  case SimpleType::UShort:
    return index_of<std::uint16_t>();
  case SimpleType::Long:
    return index_of<std::int32_t>();
  case SimpleType::ULong:
    return index_of<std::uint32_t>();
  case SimpleType::LongLong:
    return index_of<std::int64_t>();
  case SimpleType::ULongLong:
    return index_of<std::uint64_t>();
  case SimpleType::Float:
    return index_of<float>();
  case SimpleType::Double:
    return index_of<double>();
  case SimpleType::String:
  case SimpleType::ObjRef:
    return index_of<std::string>();
  case SimpleType::UtcTime:
    return index_of<profile::UtcTime>();
  }
  return std::variant_npos;
}

// The C++ type that binds the Scalar alternative at `index`.
std::string_view cxx_type_name(std::size_t index) {
  constexpr std::array<std::string_view, 14> kNames{
      "bool",         "char",          "std::uint8_t",     "std::int16_t",        "std::uint16_t",
      "std::int32_t", "std::uint32_t", "std::int64_t",     "std::uint64_t",       "float",
      "double",       "std::string",   "profile::UtcTime", "std::complex<double>"};
  return index < kNames.size() ? kNames[index] : "?";
}

std::string type_label(TypeSpec spec) {
  return spec.complex ? fmt::format("complex {}", to_string(spec.type))
                      : std::string(to_string(spec.type));
}

std::optional<std::string> type_mismatch(TypeSpec spec, std::size_t index) {
  if (scalar_index(spec) == index)
    return std::nullopt;
  return fmt::format("the variable holds {}, the PRF type {} needs {}", cxx_type_name(index),
                     type_label(spec), cxx_type_name(scalar_index(spec)));
}

template <typename Simple, typename Sequence, typename Variant>
std::optional<std::string> form_mismatch(const Variant &definition, std::size_t index,
                                         bool sequence) {
  if (const auto *s = std::get_if<Simple>(&definition); s != nullptr && !sequence)
    return type_mismatch(s->type, index);
  if (const auto *s = std::get_if<Sequence>(&definition); s != nullptr && sequence)
    return type_mismatch(s->type, index);
  return sequence ? "the variable is a std::vector, the PRF property is not a simplesequence"
                  : "the variable is a single value, the PRF property is not a simple";
}

} // namespace

std::optional<std::string> simple_mismatch(const profile::PropertyDefinition &definition,
                                           std::size_t index, bool sequence) {
  return form_mismatch<profile::SimpleProperty, profile::SimpleSequenceProperty>(definition, index,
                                                                                 sequence);
}

std::optional<std::string> member_mismatch(const profile::StructMember &member, std::size_t index,
                                           bool sequence) {
  return form_mismatch<profile::SimpleProperty, profile::SimpleSequenceProperty>(member, index,
                                                                                 sequence);
}

std::optional<std::string> struct_mismatch(
    const profile::StructProperty &definition, const std::vector<std::string> &field_ids,
    const std::function<std::optional<std::string>(std::size_t, const profile::StructMember &)>
        &check) {
  for (std::size_t i = 0; i < field_ids.size(); ++i) {
    const auto *member = definition.find_member(field_ids[i]);
    if (member == nullptr)
      return fmt::format("field \"{}\" is not a member of the PRF struct", field_ids[i]);
    if (auto why = check(i, *member))
      return fmt::format("member \"{}\": {}", field_ids[i], *why);
  }
  for (const auto &member : definition.members) {
    const std::string &id = profile::common_of(member).id;
    if (std::find(field_ids.begin(), field_ids.end(), id) == field_ids.end())
      return fmt::format("member \"{}\" has no field", id);
  }
  return std::nullopt;
}

} // namespace detail

namespace {

using Json = nlohmann::json;
using profile::AccessMode;
using profile::PropertyKind;

bool configurable(const profile::PropertyCommon &p) {
  return p.has_kind(PropertyKind::Configure) || p.has_kind(PropertyKind::Property);
}

bool queryable(const profile::PropertyCommon &p) {
  return p.mode != AccessMode::WriteOnly &&
         (configurable(p) || p.has_kind(PropertyKind::ExecParam));
}

std::string kinds_text(const profile::PropertyCommon &p) {
  std::string text;
  for (auto kind : p.kinds)
    text += (text.empty() ? "" : ", ") + std::string(profile::to_string(kind));
  return text;
}

// Why `value` cannot configure the property `id`, if it cannot; else its typed value.
tl::expected<profile::PropertyValue, std::string>
checked_value(const profile::PropertyDefinition *definition, const std::string &id,
              const Json &value) {
  if (definition == nullptr)
    return tl::unexpected(fmt::format("unknown property \"{}\"", id));
  const auto &common = profile::common_of(*definition);
  if (common.mode == AccessMode::ReadOnly)
    return tl::unexpected(fmt::format("property \"{}\" is read-only", id));
  if (!configurable(common))
    return tl::unexpected(
        fmt::format("property \"{}\" is not configurable (kind {})", id, kinds_text(common)));
  return profile::from_json(*definition, value);
}

void merge(profile::StructValue &into, const profile::StructValue &from) {
  for (const auto &[id, member] : from.members) {
    auto it = std::find_if(into.members.begin(), into.members.end(),
                           [&id = id](const auto &m) { return m.first == id; });
    if (it == into.members.end())
      into.members.emplace_back(id, member);
    else
      it->second = member;
  }
}

} // namespace

std::vector<std::string> PropertySet::bound_ids() const {
  std::vector<std::string> ids;
  for (const auto &[id, binding] : bindings_)
    ids.push_back(id);
  return ids;
}

void PropertySet::bind(std::string id, std::unique_ptr<PropertyBinding> binding) {
  bindings_[std::move(id)] = std::move(binding);
}

Expected<void> PropertySet::load(std::vector<profile::PropertyDefinition> definitions) {
  definitions_ = std::move(definitions);
  Error error;
  // Bound but not defined: as `rsca validate` finds it from the code's description.
  for (auto &misfit : profile::code_misfits({{}, bound_ids()}, nullptr, definitions_))
    error.add({{"component", 0, 0}, "binding", std::move(misfit)});
  for (const auto &[id, binding] : bindings_) {
    const auto *definition = find(id);
    if (definition == nullptr)
      continue;
    if (auto why = binding->mismatch(*definition))
      error.add({{"component", 0, 0}, "binding", fmt::format("property \"{}\": {}", id, *why)});
  }
  if (!error.empty())
    return tl::unexpected(std::move(error));
  for (const auto &definition : definitions_)
    if (auto value = profile::default_value(definition))
      apply(profile::common_of(definition).id, *value);
  return {};
}

const profile::PropertyDefinition *PropertySet::find(std::string_view id) const {
  for (const auto &d : definitions_)
    if (profile::common_of(d).id == id)
      return &d;
  return nullptr;
}

std::function<void()> PropertySet::apply(const std::string &id,
                                         const profile::PropertyValue &value) {
  if (auto it = bindings_.find(id); it != bindings_.end())
    return it->second->set(value);
  auto it = values_.find(id);
  auto *current = it == values_.end() ? nullptr : std::get_if<profile::StructValue>(&it->second);
  if (current != nullptr && std::holds_alternative<profile::StructValue>(value))
    merge(*current, std::get<profile::StructValue>(value));
  else
    values_.insert_or_assign(id, value);
  return {};
}

tl::expected<void, std::string> PropertySet::apply_text(const std::string &id,
                                                        const std::string &text) {
  const auto *definition = find(id);
  if (definition == nullptr)
    return tl::unexpected(fmt::format("unknown property \"{}\"", id));
  const auto *simple = std::get_if<profile::SimpleProperty>(definition);
  if (simple == nullptr)
    return tl::unexpected(fmt::format("property \"{}\" is not a simple", id));
  Json json = text; // an enumeration label stays text
  const bool is_label = std::any_of(simple->enumerations.begin(), simple->enumerations.end(),
                                    [&](const auto &e) { return e.label == text; });
  if (!is_label) {
    auto scalar = profile::parse_scalar(simple->type, text);
    if (!scalar)
      return tl::unexpected(fmt::format("property \"{}\": {}", id, scalar.error()));
    json = profile::to_json(*scalar);
  }
  auto value = profile::from_json(*definition, json);
  if (!value)
    return tl::unexpected(value.error());
  apply(id, *value);
  return {};
}

control::CallResult<std::vector<std::function<void()>>>
PropertySet::configure(const Json &properties) {
  if (!properties.is_object())
    return control::call_error(control::Status::BadRequest,
                               "\"properties\" must be an object of property ids and values");
  std::vector<std::pair<std::string, profile::PropertyValue>> values;
  std::string errors;
  for (const auto &[id, json] : properties.items()) {
    auto value = checked_value(find(id), id, json);
    if (!value) {
      errors += (errors.empty() ? "" : "; ") + value.error();
      continue;
    }
    values.emplace_back(id, std::move(*value));
  }
  if (!errors.empty())
    return control::call_error(control::Status::BadRequest, errors);
  std::vector<std::function<void()>> notifications;
  for (const auto &[id, value] : values)
    if (auto notify = apply(id, value))
      notifications.push_back(std::move(notify));
  return notifications;
}

Json PropertySet::value_json(const profile::PropertyDefinition &definition) const {
  const std::string &id = profile::common_of(definition).id;
  if (auto it = bindings_.find(id); it != bindings_.end())
    return profile::to_json(it->second->get());
  if (auto it = values_.find(id); it != values_.end())
    return profile::to_json(it->second);
  return nullptr;
}

control::CallResult<Json> PropertySet::query(const std::vector<std::string> &ids) const {
  Json out = Json::object();
  if (ids.empty()) {
    for (const auto &definition : definitions_)
      if (queryable(profile::common_of(definition)))
        out[profile::common_of(definition).id] = value_json(definition);
    return out;
  }
  for (const auto &id : ids) {
    const auto *definition = find(id);
    if (definition == nullptr)
      return control::call_error(control::Status::BadRequest,
                                 fmt::format("unknown property \"{}\"", id));
    if (profile::common_of(*definition).mode == AccessMode::WriteOnly)
      return control::call_error(control::Status::BadRequest,
                                 fmt::format("property \"{}\" is write-only", id));
    out[id] = value_json(*definition);
  }
  return out;
}

} // namespace rsca::component
