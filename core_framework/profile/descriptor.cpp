#include "profile/descriptor.hpp"

#include <array>

#include <fmt/format.h>

namespace rsca::profile {
namespace {

struct DescriptorInfo {
  DescriptorType type;
  std::string_view name;
  std::string_view root;
};

constexpr std::array<DescriptorInfo, 7> kDescriptors{{
    {DescriptorType::SAD, "SAD", "softwareassembly"},
    {DescriptorType::SPD, "SPD", "softpkg"},
    {DescriptorType::SCD, "SCD", "softwarecomponent"},
    {DescriptorType::PRF, "PRF", "properties"},
    {DescriptorType::DCD, "DCD", "deviceconfiguration"},
    {DescriptorType::DMD, "DMD", "domainmanagerconfiguration"},
    {DescriptorType::DPD, "DPD", "devicepkg"},
}};

// Converts a typed result into the Descriptor variant.
template <typename T>
Expected<Descriptor> widen(Expected<T> result) {
  if (!result)
    return tl::unexpected(std::move(result.error()));
  return Descriptor(std::move(*result));
}

} // namespace

std::string_view to_string(DescriptorType type) {
  return kDescriptors[static_cast<std::size_t>(type)].name;
}

std::optional<DescriptorType> descriptor_type_of_root(std::string_view root_element) {
  for (const auto &d : kDescriptors)
    if (d.root == root_element)
      return d.type;
  return std::nullopt;
}

DescriptorType type_of(const Descriptor &descriptor) {
  return static_cast<DescriptorType>(descriptor.index());
}

Expected<Descriptor> read_descriptor(const XmlDocument &document) {
  auto type = descriptor_type_of_root(document.root.name);
  if (!type)
    return make_error({document.file, document.root.line, document.root.column}, "schema",
                      fmt::format("<{}> is not the root of a domain profile", document.root.name));
  switch (*type) {
  case DescriptorType::SAD:
    return widen(read_sad(document));
  case DescriptorType::SPD:
    return widen(read_spd(document));
  case DescriptorType::SCD:
    return widen(read_scd(document));
  case DescriptorType::PRF:
    return widen(read_prf(document));
  case DescriptorType::DCD:
    return widen(read_dcd(document));
  case DescriptorType::DMD:
    return widen(read_dmd(document));
  case DescriptorType::DPD:
    return widen(read_dpd(document));
  }
  return make_error({document.file, 0, 0}, "schema", "unknown descriptor type");
}

Expected<Descriptor> read_descriptor(const std::filesystem::path &file) {
  return read_xml_profile(file).and_then(
      [](const XmlDocument &doc) { return read_descriptor(doc); });
}

} // namespace rsca::profile
