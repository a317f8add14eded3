// SAD: an application — its components, their placement, connections, and RSCA's latency paths.
#pragma once

#include "common/diagnostic.hpp"

#include <string>
#include <vector>

#include "profile/assembly.hpp"

namespace rsca::profile {

struct ExternalPort {
  enum class Kind : std::uint8_t { Uses, Provides, SupportedInterface };
  std::string external_name; // defaults to the port name
  std::string port;          // port name, or the supported interface's repid
  Kind kind = Kind::Uses;
  std::string component_ref;
  SourceLocation where;
};

struct ExternalProperty {
  std::string component_ref;
  std::string property_id;
  std::string external_id; // defaults to property_id
  SourceLocation where;
};

// RSCA extension: an end-to-end latency bound along a chain of components, in data-flow order.
struct LatencyPath {
  std::string id;
  Duration bound;
  std::vector<std::string> components;
  std::vector<SourceLocation> component_where; // where each component is named
  SourceLocation where;
};

struct SoftwareAssembly {
  std::string file;
  std::string id;
  std::string name;
  std::string version;
  std::string description;
  std::vector<ComponentFile> component_files;
  std::vector<ComponentPlacement> placements;
  std::vector<HostCollocation> host_collocations;
  std::string assembly_controller; // componentinstantiation id
  SourceLocation assembly_controller_where;
  std::vector<Connection> connections;
  std::vector<ExternalPort> external_ports;
  std::vector<ExternalProperty> external_properties;
  std::vector<UsesDevice> uses_device_dependencies;
  std::vector<LatencyPath> latency_paths;
  std::vector<Diagnostic> warnings; // what reading it tolerated (see detail::ReadContext::warn)
  bool redhawk = false; // written for REDHAWK (its SCA DOCTYPE): read leniently, see XmlDocument

  const ComponentFile *find_component_file(std::string_view id) const;
  // The instantiation with that id and the placement holding it; nullptr when none.
  const ComponentInstantiation *
  find_instantiation(std::string_view id, const ComponentPlacement **placement = nullptr) const;
};

} // namespace rsca::profile
