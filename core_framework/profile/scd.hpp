// SCD: a component's interfaces and ports.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/diagnostic.hpp"

namespace rsca::profile {

enum class PortDirection : std::uint8_t { Uses, Provides };
// "uses" and "provides", as the SCD's elements are named.
std::string_view to_string(PortDirection direction);
std::optional<PortDirection> port_direction_from_name(std::string_view name);

// Whether `repid` is a CF interface whose operations a ResourceUsesPort calls on a component's
// control endpoint (component/resource_port.hpp): Resource (start, stop) and the PropertySet
// (configure, query) and LifeCycle it inherits. A uses port of one of them is connected to
// another component's supported interface.
bool is_control_interface(std::string_view repid);

struct PortDefinition {
  std::string name;
  std::string repid;
  PortDirection direction = PortDirection::Uses;
  std::vector<std::string> port_types; // "data", "control", "responses", "test"
  std::string description;
  SourceLocation where;
};

struct SupportedInterface {
  std::string repid;
  std::string name;
};

struct InterfaceDefinition {
  std::string name;
  std::string repid;
  std::vector<std::string> inherits; // repids
};

struct SoftwareComponent {
  std::string file;
  std::string corba_version;
  std::string component_repid;
  std::string component_type; // resource, device, executabledevice, ...
  std::optional<std::string> property_file;
  std::vector<SupportedInterface> supported_interfaces;
  std::vector<PortDefinition> ports;
  std::vector<InterfaceDefinition> interfaces;
  std::vector<Diagnostic> warnings; // what reading it tolerated (see detail::ReadContext::warn)
  bool redhawk = false; // written for REDHAWK (its SCA DOCTYPE): read leniently, see XmlDocument

  const PortDefinition *find_port(std::string_view name, PortDirection direction) const;
  // True when `repid` names this component's own interface or one it supports or inherits.
  bool supports(std::string_view repid) const;
};

} // namespace rsca::profile
