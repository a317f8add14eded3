// Any one of the seven descriptor types, read from a file whose root element says which.
#pragma once

#include <filesystem>
#include <optional>
#include <string_view>
#include <variant>

#include "common/diagnostic.hpp"
#include "profile/dcd.hpp"
#include "profile/dmd.hpp"
#include "profile/dpd.hpp"
#include "profile/prf.hpp"
#include "profile/sad.hpp"
#include "profile/scd.hpp"
#include "profile/spd.hpp"
#include "profile/xml_document.hpp"

namespace rsca::profile {

enum class DescriptorType : std::uint8_t { SAD, SPD, SCD, PRF, DCD, DMD, DPD };

std::string_view to_string(DescriptorType type);
std::optional<DescriptorType> descriptor_type_of_root(std::string_view root_element);

using Descriptor = std::variant<SoftwareAssembly, SoftPkg, SoftwareComponent, Properties,
                                DeviceConfiguration, DomainManagerConfiguration, DevicePkg>;
DescriptorType type_of(const Descriptor &descriptor);

// Reads, validates and checks one file on its own (references to other files are not followed;
// see ProfileLoader). Never yields a partial model.
Expected<Descriptor> read_descriptor(const std::filesystem::path &file);
Expected<Descriptor> read_descriptor(const XmlDocument &document);

// The same, when the caller needs one type: a file of another type is an error that says so.
Expected<SoftwareAssembly> read_sad(const XmlDocument &document);
Expected<SoftPkg> read_spd(const XmlDocument &document);
Expected<SoftwareComponent> read_scd(const XmlDocument &document);
Expected<Properties> read_prf(const XmlDocument &document);
Expected<DeviceConfiguration> read_dcd(const XmlDocument &document);
Expected<DomainManagerConfiguration> read_dmd(const XmlDocument &document);
Expected<DevicePkg> read_dpd(const XmlDocument &document);

} // namespace rsca::profile
