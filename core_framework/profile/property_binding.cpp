#include "profile/property_binding.hpp"

#include <algorithm>

#include <fmt/format.h>

namespace rsca::profile {
namespace {

// Binding errors carry the rule they break, as the PRF reader's own errors do.
struct BindError {
  std::string rule;
  std::string message;
};
template <typename T>
using Bound = tl::expected<T, BindError>;
tl::unexpected<BindError> bind_error(std::string rule, std::string message) {
  return tl::unexpected(BindError{std::move(rule), std::move(message)});
}

std::string_view form_name(const PropertyDefinition &d) {
  constexpr std::string_view names[] = {"simple", "simplesequence", "struct", "structsequence"};
  return names[d.index()];
}

std::string_view ref_form_name(const PropertyRef &r) {
  constexpr std::string_view names[] = {"simpleref", "simplesequenceref", "structref",
                                        "structsequenceref"};
  return names[r.index()];
}

// Checks one value against a simple definition's type, enumerations and range.
Bound<Scalar> bind_scalar(const std::string &id, TypeSpec type,
                          const std::optional<ValueRange> &range,
                          const std::vector<Enumeration> &enumerations, const std::string &text) {
  // REDHAWK lets a value name an enumeration label instead of the value itself.
  for (const auto &e : enumerations)
    if (e.label == text)
      return e.value;
  auto value = parse_scalar(type, text);
  if (!value)
    return bind_error("value", fmt::format("property \"{}\": {}", id, value.error()));
  if (range && !(satisfies(Action::Ge, *value, range->min).value_or(true) &&
                 satisfies(Action::Le, *value, range->max).value_or(true)))
    return bind_error("range",
                      fmt::format("property \"{}\": {} is outside its range {}..{}", id, text,
                                  format_scalar(range->min), format_scalar(range->max)));
  return *value;
}

Bound<std::vector<Scalar>> bind_sequence(const SimpleSequenceProperty &d,
                                         const SimpleSequenceRef &r) {
  std::vector<Scalar> values;
  values.reserve(r.values.size());
  for (const auto &text : r.values) {
    auto v = bind_scalar(d.id, d.type, d.range, {}, text);
    if (!v)
      return tl::unexpected(v.error());
    values.push_back(std::move(*v));
  }
  return values;
}

Bound<StructValue> bind_struct(const StructProperty &d, const StructRef &r) {
  StructValue value;
  for (const auto &member_ref : r.members) {
    const std::string &refid =
        std::visit([](const auto &m) -> const std::string & { return m.refid; }, member_ref);
    const StructMember *member = d.find_member(refid);
    if (member == nullptr)
      return bind_error("unknown-property",
                        fmt::format("struct \"{}\" has no member \"{}\"", d.id, refid));
    if (const auto *simple = std::get_if<SimpleProperty>(member)) {
      const auto *simple_ref = std::get_if<SimpleRef>(&member_ref);
      if (simple_ref == nullptr)
        return bind_error("value", fmt::format("member \"{}\" is a simple: use simpleref", refid));
      auto v =
          bind_scalar(refid, simple->type, simple->range, simple->enumerations, simple_ref->value);
      if (!v)
        return tl::unexpected(v.error());
      value.members.emplace_back(refid, std::move(*v));
      continue;
    }
    const auto *seq_ref = std::get_if<SimpleSequenceRef>(&member_ref);
    if (seq_ref == nullptr)
      return bind_error(
          "value", fmt::format("member \"{}\" is a simplesequence: use simplesequenceref", refid));
    auto v = bind_sequence(std::get<SimpleSequenceProperty>(*member), *seq_ref);
    if (!v)
      return tl::unexpected(v.error());
    value.members.emplace_back(refid, std::move(*v));
  }
  return value;
}

template <typename T>
Bound<PropertyValue> widen(Bound<T> v) {
  if (!v)
    return tl::unexpected(v.error());
  return PropertyValue(std::move(*v));
}

Bound<PropertyValue> bind(const PropertyDefinition &definition, const PropertyRef &ref) {
  if (const auto *d = std::get_if<SimpleProperty>(&definition))
    if (const auto *r = std::get_if<SimpleRef>(&ref))
      return widen(bind_scalar(d->id, d->type, d->range, d->enumerations, r->value));
  if (const auto *d = std::get_if<SimpleSequenceProperty>(&definition))
    if (const auto *r = std::get_if<SimpleSequenceRef>(&ref))
      return widen(bind_sequence(*d, *r));
  if (const auto *d = std::get_if<StructProperty>(&definition))
    if (const auto *r = std::get_if<StructRef>(&ref))
      return widen(bind_struct(*d, *r));
  if (const auto *d = std::get_if<StructSequenceProperty>(&definition)) {
    if (const auto *r = std::get_if<StructSequenceRef>(&ref)) {
      std::vector<StructValue> values;
      for (const auto &item : r->values) {
        auto v = bind_struct(d->element, item);
        if (!v)
          return tl::unexpected(v.error());
        values.push_back(std::move(*v));
      }
      return PropertyValue(std::move(values));
    }
  }
  return bind_error("value", fmt::format("property \"{}\" is a {}, but is given as a {}",
                                         common_of(definition).id, form_name(definition),
                                         ref_form_name(ref)));
}

} // namespace

bool is_empty_override(const SimpleProperty &definition, const PropertyRef &ref) {
  const auto *value = std::get_if<SimpleRef>(&ref);
  if (value == nullptr)
    return false;
  const bool textual =
      definition.type.type == SimpleType::String || definition.type.type == SimpleType::ObjRef;
  return !textual && value->value.find_first_not_of(" \t\r\n") == std::string::npos;
}

bool names_unknown_members_only(const Error &binding) {
  const auto &d = binding.diagnostics();
  return !d.empty() && std::all_of(d.begin(), d.end(), [](const Diagnostic &one) {
    return one.rule == "unknown-property";
  });
}

bool is_empty_override(const PropertyDefinition &definition, const PropertyRef &ref) {
  const auto *simple = std::get_if<SimpleProperty>(&definition);
  return simple != nullptr && is_empty_override(*simple, ref);
}

Expected<PropertyValue> bind_property(const PropertyDefinition &definition,
                                      const PropertyRef &ref) {
  auto value = bind(definition, ref);
  if (!value)
    return make_error(location_of(ref), value.error().rule, value.error().message);
  return std::move(*value);
}

} // namespace rsca::profile
