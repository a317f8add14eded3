// DMD: the domain — its name and its DomainManager package.
#pragma once

#include <string>

#include "profile/spd.hpp"

namespace rsca::profile {

struct DomainManagerConfiguration {
  std::string file;
  std::string id;
  std::string name;
  std::string description;
  LocalFile domain_manager_softpkg;
};

} // namespace rsca::profile
