// DMD: the domain — its name and its DomainManager package.
#pragma once

#include "common/diagnostic.hpp"

#include <string>

#include "profile/spd.hpp"

namespace rsca::profile {

struct DomainManagerConfiguration {
  std::string file;
  std::string id;
  std::string name;
  std::string description;
  LocalFile domain_manager_softpkg;
  std::vector<Diagnostic> warnings; // what reading it tolerated (see detail::ReadContext::warn)
  bool redhawk = false; // written for REDHAWK (its SCA DOCTYPE): read leniently, see XmlDocument
};

} // namespace rsca::profile
