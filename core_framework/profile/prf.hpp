// PRF: property definitions (simple, simplesequence, struct, structsequence) with their kinds,
// actions, enumerations, ranges and units, and the typed values they hold.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "common/diagnostic.hpp"
#include "profile/property_value.hpp"

namespace rsca::profile {

enum class PropertyKind : std::uint8_t {
  Allocation,
  Property,
  Configure,
  Test,
  ExecParam,
  FactoryParam,
  Event,
  Message,
};
enum class AccessMode : std::uint8_t { ReadWrite, ReadOnly, WriteOnly };

std::optional<PropertyKind> property_kind_from_name(std::string_view name);
std::string_view to_string(PropertyKind kind);
std::string_view to_string(AccessMode mode);
std::optional<AccessMode> access_mode_from_name(std::string_view name);

// A value of a struct: each member by id, a scalar or a sequence.
using MemberValue = std::variant<Scalar, std::vector<Scalar>>;
struct StructValue {
  std::vector<std::pair<std::string, MemberValue>> members;
};
// The value of any property form.
using PropertyValue =
    std::variant<Scalar, std::vector<Scalar>, StructValue, std::vector<StructValue>>;

std::string format_value(const PropertyValue &value);

struct PropertyCommon {
  std::string id;
  std::string name;
  std::string description;
  AccessMode mode = AccessMode::ReadWrite;
  std::vector<PropertyKind> kinds; // empty in the file means SCA's default, "configure"
  SourceLocation where;

  bool has_kind(PropertyKind kind) const;
  // The name when given, else the id: what users see.
  const std::string &label() const { return name.empty() ? id : name; }
};

struct Enumeration {
  std::string label;
  Scalar value;
};

struct ValueRange {
  Scalar min;
  Scalar max;
};

struct SimpleProperty : PropertyCommon {
  TypeSpec type;
  std::optional<Scalar> value;
  std::string units;
  std::optional<ValueRange> range;
  std::vector<Enumeration> enumerations;
  std::optional<Action> action;
  bool commandline = false; // REDHAWK: an execparam passed on the command line
  bool optional = false;
};

struct SimpleSequenceProperty : PropertyCommon {
  TypeSpec type;
  std::optional<std::vector<Scalar>> values;
  std::string units;
  std::optional<ValueRange> range;
  std::optional<Action> action;
  bool optional = false;
};

using StructMember = std::variant<SimpleProperty, SimpleSequenceProperty>;
const PropertyCommon &common_of(const StructMember &member);

struct StructProperty : PropertyCommon {
  std::vector<StructMember> members;
  std::optional<StructValue> value; // from the members' own <value>s, when any is given

  const StructMember *find_member(std::string_view member_id) const;
};

struct StructSequenceProperty : PropertyCommon {
  StructProperty element; // the struct each entry follows
  std::vector<StructValue> values;
};

using PropertyDefinition =
    std::variant<SimpleProperty, SimpleSequenceProperty, StructProperty, StructSequenceProperty>;
const PropertyCommon &common_of(const PropertyDefinition &property);
// The default value of a definition, if the PRF gives one.
std::optional<PropertyValue> default_value(const PropertyDefinition &property);

struct Properties {
  std::string file;
  std::vector<PropertyDefinition> properties;
  std::vector<Diagnostic> warnings; // what reading it tolerated (see detail::ReadContext::warn)
  bool redhawk = false; // written for REDHAWK (its SCA DOCTYPE): read leniently, see XmlDocument

  const PropertyDefinition *find(std::string_view id) const;
};

} // namespace rsca::profile
