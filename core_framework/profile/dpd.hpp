// DPD: the hardware a device package drives.
#pragma once

#include "common/diagnostic.hpp"

#include <optional>
#include <string>
#include <vector>

#include "profile/spd.hpp"

namespace rsca::profile {

struct HardwareDevice {
  std::string id;
  std::string name;
  std::string version;
  std::optional<LocalFile> property_file;
  std::string description;
  std::string manufacturer;
  std::string model_number;
  std::vector<std::string> device_classes;
  std::vector<HardwareDevice> children;
};

struct DevicePkg {
  std::string file;
  std::string id;
  std::string name;
  std::string version;
  std::string title;
  std::vector<std::string> authors;
  std::string description;
  HardwareDevice hardware;
  std::vector<Diagnostic> warnings; // what reading it tolerated (see detail::ReadContext::warn)
  bool redhawk = false; // written for REDHAWK (its SCA DOCTYPE): read leniently, see XmlDocument
};

} // namespace rsca::profile
