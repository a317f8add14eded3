// Look-ups and names of the profile model's types.
#include <algorithm>
#include <array>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "profile/assembly.hpp"
#include "profile/dcd.hpp"
#include "profile/prf.hpp"
#include "profile/property_refs.hpp"
#include "profile/sad.hpp"
#include "profile/scd.hpp"
#include "profile/spd.hpp"

namespace rsca::profile {
namespace {

template <class... Ts>
struct Overloaded : Ts... {
  using Ts::operator()...;
};
template <class... Ts>
Overloaded(Ts...) -> Overloaded<Ts...>;

constexpr std::pair<std::string_view, PropertyKind> kKinds[] = {
    {"allocation", PropertyKind::Allocation}, {"property", PropertyKind::Property},
    {"configure", PropertyKind::Configure},   {"test", PropertyKind::Test},
    {"execparam", PropertyKind::ExecParam},   {"factoryparam", PropertyKind::FactoryParam},
    {"event", PropertyKind::Event},           {"message", PropertyKind::Message}};

std::string format_sequence(const std::vector<Scalar> &values) {
  std::vector<std::string> items;
  items.reserve(values.size());
  for (const auto &v : values)
    items.push_back(format_scalar(v));
  return fmt::format("[{}]", fmt::join(items, ", "));
}

std::string format_struct(const StructValue &value) {
  std::vector<std::string> items;
  for (const auto &[id, member] : value.members)
    items.push_back(fmt::format(
        "{}={}", id,
        std::visit(Overloaded{[](const Scalar &s) { return format_scalar(s); },
                              [](const std::vector<Scalar> &s) { return format_sequence(s); }},
                   member)));
  return fmt::format("{{{}}}", fmt::join(items, ", "));
}

} // namespace

std::optional<PropertyKind> property_kind_from_name(std::string_view name) {
  for (const auto &[key, kind] : kKinds)
    if (key == name)
      return kind;
  return std::nullopt;
}

std::string_view to_string(PropertyKind kind) {
  for (const auto &[key, k] : kKinds)
    if (k == kind)
      return key;
  return "?";
}

std::string_view to_string(AccessMode mode) {
  switch (mode) {
  case AccessMode::ReadOnly:
    return "readonly";
  case AccessMode::WriteOnly:
    return "writeonly";
  case AccessMode::ReadWrite:
    break;
  }
  return "readwrite";
}

std::optional<AccessMode> access_mode_from_name(std::string_view name) {
  for (auto mode : {AccessMode::ReadWrite, AccessMode::ReadOnly, AccessMode::WriteOnly})
    if (to_string(mode) == name)
      return mode;
  return std::nullopt;
}

std::string_view to_string(PortDirection direction) {
  return direction == PortDirection::Uses ? "uses" : "provides";
}

std::optional<PortDirection> port_direction_from_name(std::string_view name) {
  for (auto direction : {PortDirection::Uses, PortDirection::Provides})
    if (to_string(direction) == name)
      return direction;
  return std::nullopt;
}

std::string format_value(const PropertyValue &value) {
  return std::visit(Overloaded{[](const Scalar &s) { return format_scalar(s); },
                               [](const std::vector<Scalar> &s) { return format_sequence(s); },
                               [](const StructValue &s) { return format_struct(s); },
                               [](const std::vector<StructValue> &s) {
                                 std::vector<std::string> items;
                                 for (const auto &v : s)
                                   items.push_back(format_struct(v));
                                 return fmt::format("[{}]", fmt::join(items, ", "));
                               }},
                    value);
}

bool PropertyCommon::has_kind(PropertyKind kind) const {
  if (kinds.empty())
    return kind == PropertyKind::Configure;
  return std::find(kinds.begin(), kinds.end(), kind) != kinds.end();
}

const PropertyCommon &common_of(const StructMember &member) {
  return std::visit([](const auto &m) -> const PropertyCommon & { return m; }, member);
}

const PropertyCommon &common_of(const PropertyDefinition &property) {
  return std::visit([](const auto &p) -> const PropertyCommon & { return p; }, property);
}

std::optional<PropertyValue> default_value(const PropertyDefinition &property) {
  return std::visit(Overloaded{[](const SimpleProperty &p) -> std::optional<PropertyValue> {
                                 if (!p.value)
                                   return std::nullopt;
                                 return PropertyValue(*p.value);
                               },
                               [](const SimpleSequenceProperty &p) -> std::optional<PropertyValue> {
                                 if (!p.values)
                                   return std::nullopt;
                                 return PropertyValue(*p.values);
                               },
                               [](const StructProperty &p) -> std::optional<PropertyValue> {
                                 if (!p.value)
                                   return std::nullopt;
                                 return PropertyValue(*p.value);
                               },
                               [](const StructSequenceProperty &p) -> std::optional<PropertyValue> {
                                 if (p.values.empty())
                                   return std::nullopt;
                                 return PropertyValue(p.values);
                               }},
                    property);
}

const StructMember *StructProperty::find_member(std::string_view member_id) const {
  for (const auto &m : members)
    if (common_of(m).id == member_id)
      return &m;
  return nullptr;
}

const PropertyDefinition *Properties::find(std::string_view id) const {
  for (const auto &p : properties)
    if (common_of(p).id == id)
      return &p;
  return nullptr;
}

const std::string &refid_of(const PropertyRef &ref) {
  return std::visit([](const auto &r) -> const std::string & { return r.refid; }, ref);
}

const SourceLocation &location_of(const PropertyRef &ref) {
  return std::visit([](const auto &r) -> const SourceLocation & { return r.where; }, ref);
}

const PortDefinition *SoftwareComponent::find_port(std::string_view port_name,
                                                   PortDirection direction) const {
  for (const auto &p : ports)
    if (p.name == port_name && p.direction == direction)
      return &p;
  return nullptr;
}

bool is_control_interface(std::string_view repid) {
  static constexpr std::array<std::string_view, 3> kServed{
      "IDL:CF/Resource:1.0", "IDL:CF/PropertySet:1.0", "IDL:CF/LifeCycle:1.0"};
  return std::find(kServed.begin(), kServed.end(), repid) != kServed.end();
}

bool SoftwareComponent::supports(std::string_view repid) const {
  if (component_repid == repid)
    return true;
  for (const auto &s : supported_interfaces)
    if (s.repid == repid)
      return true;
  for (const auto &i : interfaces)
    for (const auto &inherited : i.inherits)
      if (inherited == repid)
        return true;
  return false;
}

std::string_view to_string(CodeType type) {
  constexpr std::string_view names[] = {"Executable", "SharedLibrary", "KernelModule", "Driver",
                                        "Node"};
  return names[static_cast<std::size_t>(type)];
}

const Implementation *SoftPkg::find_implementation(std::string_view impl_id) const {
  for (const auto &i : implementations)
    if (i.id == impl_id)
      return &i;
  return nullptr;
}

std::string_view to_string(Criticality v) {
  constexpr std::string_view names[] = {"low", "medium", "high", "safety"};
  return names[static_cast<std::size_t>(v)];
}
std::string_view to_string(ProcessorAffinity::Class v) {
  constexpr std::string_view names[] = {"cpu", "socket", "nic", "nice"};
  return names[static_cast<std::size_t>(v)];
}
std::string_view to_string(Reliability v) {
  return v == Reliability::Reliable ? "reliable" : "besteffort";
}
std::string_view to_string(Durability v) {
  constexpr std::string_view names[] = {"volatile", "transientlocal", "transient", "persistent"};
  return names[static_cast<std::size_t>(v)];
}
std::string_view to_string(History v) {
  return v == History::KeepAll ? "keepall" : "keeplast";
}
std::string_view to_string(Liveliness v) {
  constexpr std::string_view names[] = {"automatic", "manualbyparticipant", "manualbytopic"};
  return names[static_cast<std::size_t>(v)];
}
std::string_view to_string(Transport v) {
  switch (v) {
  case Transport::Direct:
    return "direct";
  case Transport::Tcp:
    return "tcp";
  case Transport::Node:
    break;
  }
  return "node";
}

std::string_view to_string(Ownership v) {
  return v == Ownership::Exclusive ? "exclusive" : "shared";
}

const ComponentFile *SoftwareAssembly::find_component_file(std::string_view file_id) const {
  for (const auto &f : component_files)
    if (f.id == file_id)
      return &f;
  return nullptr;
}

const ComponentInstantiation *
SoftwareAssembly::find_instantiation(std::string_view instance_id,
                                     const ComponentPlacement **placement) const {
  for (const auto &p : placements)
    for (const auto &ci : p.instantiations)
      if (ci.id == instance_id) {
        if (placement != nullptr)
          *placement = &p;
        return &ci;
      }
  return nullptr;
}

const ComponentFile *DeviceConfiguration::find_component_file(std::string_view file_id) const {
  for (const auto &f : component_files)
    if (f.id == file_id)
      return &f;
  return nullptr;
}

} // namespace rsca::profile
