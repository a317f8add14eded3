#include "profile/definition_json.hpp"

#include <stdexcept>

#include <fmt/format.h>

namespace rsca::profile {
namespace {

using Json = nlohmann::json;

// Reading throws within this file; the two public readers turn that into their error.
struct ReadError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

template <typename Enum>
Enum enum_from(const Json &json, std::optional<Enum> (*from_name)(std::string_view)) {
  const auto name = json.get<std::string>();
  if (auto value = from_name(name))
    return *value;
  throw ReadError(fmt::format("unknown name \"{}\"", name));
}

// --- values: as their profile text, read back with the declared type ---

Json scalar_json(const Scalar &value) {
  return format_scalar(value);
}

Scalar scalar_from(const Json &json, TypeSpec type) {
  auto value = parse_scalar(type, json.get<std::string>());
  if (!value)
    throw ReadError(value.error());
  return *value;
}

Json scalars_json(const std::vector<Scalar> &values) {
  Json out = Json::array();
  for (const auto &v : values)
    out.push_back(scalar_json(v));
  return out;
}

std::vector<Scalar> scalars_from(const Json &json, TypeSpec type) {
  std::vector<Scalar> out;
  for (const auto &v : json)
    out.push_back(scalar_from(v, type));
  return out;
}

Json type_json(TypeSpec type) {
  return {{"type", to_string(type.type)}, {"complex", type.complex}};
}

TypeSpec type_from(const Json &json) {
  return {enum_from(json.at("type"), &simple_type_from_name), json.at("complex").get<bool>()};
}

Json range_json(const std::optional<ValueRange> &range) {
  return range ? Json{scalar_json(range->min), scalar_json(range->max)} : Json();
}

std::optional<ValueRange> range_from(const Json &json, TypeSpec type) {
  if (json.is_null())
    return std::nullopt;
  return ValueRange{scalar_from(json.at(0), type), scalar_from(json.at(1), type)};
}

Json action_json(const std::optional<Action> &action) {
  return action ? Json(to_string(*action)) : Json();
}

std::optional<Action> action_from(const Json &json) {
  if (json.is_null())
    return std::nullopt;
  return enum_from(json, &action_from_name);
}

// --- property definitions ---

Json where_json(const SourceLocation &where) {
  return {where.file, where.line, where.column};
}

SourceLocation where_from(const Json &json) {
  return {json.at(0).get<std::string>(), json.at(1).get<int>(), json.at(2).get<int>()};
}

Json common_json(const char *shape, const PropertyCommon &p) {
  Json kinds = Json::array();
  for (auto kind : p.kinds)
    kinds.push_back(to_string(kind));
  return {{"shape", shape},
          {"id", p.id},
          {"name", p.name},
          {"description", p.description},
          {"mode", to_string(p.mode)},
          {"kinds", kinds},
          {"where", where_json(p.where)}};
}

void read_common(const Json &json, PropertyCommon &p) {
  p.id = json.at("id").get<std::string>();
  p.name = json.at("name").get<std::string>();
  p.description = json.at("description").get<std::string>();
  p.mode = enum_from(json.at("mode"), &access_mode_from_name);
  for (const auto &kind : json.at("kinds"))
    p.kinds.push_back(enum_from(kind, &property_kind_from_name));
  p.where = where_from(json.at("where"));
}

// What a simple and a simple sequence have alike besides the common part: a type, and units, a
// range and an action in it.
template <typename Typed>
Json typed_json(const char *shape, const Typed &p) {
  Json out = common_json(shape, p);
  out.update({{"type", type_json(p.type)},
              {"units", p.units},
              {"range", range_json(p.range)},
              {"action", action_json(p.action)},
              {"optional", p.optional}});
  return out;
}

template <typename Typed>
Typed typed_from(const Json &json) {
  Typed p;
  read_common(json, p);
  p.type = type_from(json.at("type"));
  p.units = json.at("units").get<std::string>();
  p.range = range_from(json.at("range"), p.type);
  p.action = action_from(json.at("action"));
  p.optional = json.at("optional").get<bool>();
  return p;
}

Json simple_json(const SimpleProperty &p) {
  Json enumerations = Json::array();
  for (const auto &e : p.enumerations)
    enumerations.push_back({e.label, scalar_json(e.value)});
  Json out = typed_json("simple", p);
  out.update({{"value", p.value ? scalar_json(*p.value) : Json()},
              {"enumerations", enumerations},
              {"commandline", p.commandline}});
  return out;
}

SimpleProperty simple_from(const Json &json) {
  auto p = typed_from<SimpleProperty>(json);
  if (!json.at("value").is_null())
    p.value = scalar_from(json.at("value"), p.type);
  for (const auto &e : json.at("enumerations"))
    p.enumerations.push_back({e.at(0).get<std::string>(), scalar_from(e.at(1), p.type)});
  p.commandline = json.at("commandline").get<bool>();
  return p;
}

Json sequence_json(const SimpleSequenceProperty &p) {
  Json out = typed_json("simplesequence", p);
  out["values"] = p.values ? scalars_json(*p.values) : Json();
  return out;
}

SimpleSequenceProperty sequence_from(const Json &json) {
  auto p = typed_from<SimpleSequenceProperty>(json);
  if (!json.at("values").is_null())
    p.values = scalars_from(json.at("values"), p.type);
  return p;
}

Json member_json(const StructMember &member) {
  if (const auto *simple = std::get_if<SimpleProperty>(&member))
    return simple_json(*simple);
  return sequence_json(std::get<SimpleSequenceProperty>(member));
}

StructMember member_from(const Json &json) {
  if (json.at("shape") == "simple")
    return simple_from(json);
  return sequence_from(json);
}

// A struct value's members as [id, value] pairs; each value is read back with its member's type.
Json struct_value_json(const StructValue &value) {
  Json out = Json::array();
  for (const auto &[id, member] : value.members) {
    const auto *scalar = std::get_if<Scalar>(&member);
    out.push_back(
        {id, scalar ? scalar_json(*scalar) : scalars_json(std::get<std::vector<Scalar>>(member))});
  }
  return out;
}

StructValue struct_value_from(const Json &json, const StructProperty &definition) {
  StructValue value;
  for (const auto &entry : json) {
    const auto id = entry.at(0).get<std::string>();
    const StructMember *member = definition.find_member(id);
    if (member == nullptr)
      throw ReadError(fmt::format("struct {} has no member {}", definition.id, id));
    if (const auto *simple = std::get_if<SimpleProperty>(member))
      value.members.emplace_back(id, scalar_from(entry.at(1), simple->type));
    else
      value.members.emplace_back(
          id, scalars_from(entry.at(1), std::get<SimpleSequenceProperty>(*member).type));
  }
  return value;
}

Json struct_json(const StructProperty &p) {
  Json out = common_json("struct", p);
  Json members = Json::array();
  for (const auto &m : p.members)
    members.push_back(member_json(m));
  out.update({{"members", members}, {"value", p.value ? struct_value_json(*p.value) : Json()}});
  return out;
}

StructProperty struct_from(const Json &json) {
  StructProperty p;
  read_common(json, p);
  for (const auto &m : json.at("members"))
    p.members.push_back(member_from(m));
  if (!json.at("value").is_null())
    p.value = struct_value_from(json.at("value"), p);
  return p;
}

Json struct_sequence_json(const StructSequenceProperty &p) {
  Json out = common_json("structsequence", p);
  Json values = Json::array();
  for (const auto &v : p.values)
    values.push_back(struct_value_json(v));
  out.update({{"element", struct_json(p.element)}, {"values", values}});
  return out;
}

StructSequenceProperty struct_sequence_from(const Json &json) {
  StructSequenceProperty p;
  read_common(json, p);
  p.element = struct_from(json.at("element"));
  for (const auto &v : json.at("values"))
    p.values.push_back(struct_value_from(v, p.element));
  return p;
}

struct DefinitionToJson {
  Json operator()(const SimpleProperty &p) const { return simple_json(p); }
  Json operator()(const SimpleSequenceProperty &p) const { return sequence_json(p); }
  Json operator()(const StructProperty &p) const { return struct_json(p); }
  Json operator()(const StructSequenceProperty &p) const { return struct_sequence_json(p); }
};

PropertyDefinition definition_from(const Json &json) {
  const auto shape = json.at("shape").get<std::string>();
  if (shape == "simple")
    return simple_from(json);
  if (shape == "simplesequence")
    return sequence_from(json);
  if (shape == "struct")
    return struct_from(json);
  if (shape == "structsequence")
    return struct_sequence_from(json);
  throw ReadError(fmt::format("unknown property shape \"{}\"", shape));
}

Properties properties_from(const Json &json) {
  Properties prf;
  prf.file = json.at("file").get<std::string>();
  for (const auto &d : json.at("definitions"))
    prf.properties.push_back(definition_from(d));
  return prf;
}

// --- the SCD ---

SoftwareComponent software_component_from(const Json &json) {
  SoftwareComponent scd;
  scd.file = json.at("file").get<std::string>();
  scd.corba_version = json.at("corba_version").get<std::string>();
  scd.component_repid = json.at("repid").get<std::string>();
  scd.component_type = json.at("type").get<std::string>();
  if (!json.at("property_file").is_null())
    scd.property_file = json.at("property_file").get<std::string>();
  for (const auto &s : json.at("supported_interfaces"))
    scd.supported_interfaces.push_back({s.at(0).get<std::string>(), s.at(1).get<std::string>()});
  for (const auto &p : json.at("ports"))
    scd.ports.push_back({p.at("name").get<std::string>(), p.at("repid").get<std::string>(),
                         enum_from(p.at("direction"), &port_direction_from_name),
                         p.at("types").get<std::vector<std::string>>(),
                         p.at("description").get<std::string>(), where_from(p.at("where"))});
  for (const auto &i : json.at("interfaces"))
    scd.interfaces.push_back({i.at("name").get<std::string>(), i.at("repid").get<std::string>(),
                              i.at("inherits").get<std::vector<std::string>>()});
  return scd;
}

// Runs a reader, its exceptions (nlohmann's and ReadError) becoming the error.
template <typename T>
tl::expected<T, std::string> reading(T (*read)(const Json &), const Json &json) {
  try {
    return read(json);
  } catch (const std::exception &e) {
    return tl::unexpected(std::string(e.what()));
  }
}

} // namespace

Json to_json(const Properties &prf) {
  Json definitions = Json::array();
  for (const auto &d : prf.properties)
    definitions.push_back(std::visit(DefinitionToJson{}, d));
  return {{"file", prf.file}, {"definitions", definitions}};
}

tl::expected<Properties, std::string> properties_from_json(const Json &json) {
  return reading(&properties_from, json);
}

Json to_json(const SoftwareComponent &scd) {
  Json ports = Json::array();
  for (const auto &p : scd.ports)
    ports.push_back({{"name", p.name},
                     {"repid", p.repid},
                     {"direction", to_string(p.direction)},
                     {"types", p.port_types},
                     {"description", p.description},
                     {"where", where_json(p.where)}});
  Json supported = Json::array();
  for (const auto &s : scd.supported_interfaces)
    supported.push_back({s.repid, s.name});
  Json interfaces = Json::array();
  for (const auto &i : scd.interfaces)
    interfaces.push_back({{"name", i.name}, {"repid", i.repid}, {"inherits", i.inherits}});
  return {{"file", scd.file},
          {"corba_version", scd.corba_version},
          {"repid", scd.component_repid},
          {"type", scd.component_type},
          {"property_file", scd.property_file ? Json(*scd.property_file) : Json()},
          {"supported_interfaces", supported},
          {"ports", ports},
          {"interfaces", interfaces}};
}

tl::expected<SoftwareComponent, std::string> software_component_from_json(const Json &json) {
  return reading(&software_component_from, json);
}

} // namespace rsca::profile
