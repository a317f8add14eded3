// SPD: a software package (component, device or library) and its implementations, with the
// RSCA resource-demand extension.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/diagnostic.hpp"
#include "common/units.hpp"
#include "profile/property_refs.hpp"

namespace rsca::profile {

// A file named inside a profile, as written, with where it was written.
struct LocalFile {
  std::string name;
  SourceLocation where;
};

enum class CodeType : std::uint8_t { Executable, SharedLibrary, KernelModule, Driver, Node };
std::string_view to_string(CodeType type);

struct Code {
  CodeType type = CodeType::Executable;
  LocalFile file;
  std::string entrypoint;
  std::optional<std::uint64_t> stack_size;
  std::optional<std::uint64_t> priority;
};

struct NamedVersion {
  std::string name;
  std::string version;
};

// A dependency on another software package, optionally on one of its implementations.
struct SoftPkgRef {
  LocalFile file;
  std::optional<std::string> implref;
  SourceLocation implref_where;
  SourceLocation where;
};

// A dependency on a property of the device the implementation is loaded on.
struct PropertyDependency {
  std::string type;
  PropertyRef requirement; // propertyref (refid + value) or simpleref/structref...
};

// A device the component uses, with the properties it must allocate there.
struct UsesDevice {
  std::string id;
  std::string type;
  std::vector<PropertyRef> requirements;
  SourceLocation where;
};

// RSCA extension: what one running instance of the implementation demands. Absent fields mean
// "no demand declared".
struct ResourceDemand {
  std::optional<double> utilization; // fraction of one CPU, 0 < u <= 1
  std::optional<Duration> execution_time;
  std::optional<Duration> period;
  std::optional<std::uint64_t> memory_bytes;
  std::optional<double> bandwidth_bps;
  SourceLocation where;
};

struct Implementation {
  std::string id;
  std::string description;
  std::optional<LocalFile> property_file;
  Code code;
  NamedVersion compiler;
  std::string programming_language;
  std::string human_language;
  NamedVersion runtime;
  std::vector<NamedVersion> os;
  std::vector<std::string> processors;
  std::vector<SoftPkgRef> softpkg_dependencies;
  std::vector<PropertyDependency> property_dependencies;
  std::vector<UsesDevice> uses_devices;
  std::optional<ResourceDemand> resource_demand;
  SourceLocation where;
};

struct SoftPkg {
  std::string file;
  std::string id;
  std::string name;
  std::string type;
  std::string version;
  std::string title;
  std::string description;
  std::vector<std::string> authors;
  std::optional<LocalFile> property_file;
  std::optional<LocalFile> descriptor; // the SCD
  std::vector<Implementation> implementations;
  std::vector<UsesDevice> uses_devices;
  std::vector<Diagnostic> warnings; // what reading it tolerated (see detail::ReadContext::warn)
  bool redhawk = false; // written for REDHAWK (its SCA DOCTYPE): read leniently, see XmlDocument

  const Implementation *find_implementation(std::string_view id) const;
};

} // namespace rsca::profile
