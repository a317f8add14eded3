// DCD: one node — its DeviceManager, the devices it starts and their properties.
#pragma once

#include "common/diagnostic.hpp"

#include <string>
#include <vector>

#include "profile/assembly.hpp"

namespace rsca::profile {

struct DeviceConfiguration {
  std::string file;
  std::string id;
  std::string name;
  std::string description;
  LocalFile device_manager_softpkg;
  std::vector<ComponentFile> component_files;
  std::vector<ComponentPlacement> placements;
  std::vector<Connection> connections;
  std::string domain_manager;       // REDHAWK's naming-service name; rsca finds the domain by DDS
  std::vector<Diagnostic> warnings; // what reading it tolerated (see detail::ReadContext::warn)
  bool redhawk = false; // written for REDHAWK (its SCA DOCTYPE): read leniently, see XmlDocument

  const ComponentFile *find_component_file(std::string_view id) const;
};

} // namespace rsca::profile
