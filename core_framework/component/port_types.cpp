#include "component/port_types.hpp"

#include <chrono>

namespace rsca::port {

std::optional<PortType> port_type_for_repid(std::string_view repid) {
  constexpr std::string_view kBulkio = "IDL:BULKIO/data";
  constexpr std::string_view kVersion = ":1.0";
  if (repid == "IDL:rsca/SampleSeq:1.0")
    return PortType::Samples;
  if (repid.size() > kBulkio.size() + kVersion.size() && repid.starts_with(kBulkio) &&
      repid.ends_with(kVersion))
    return PortType::Samples;
  if (repid == "IDL:rsca/PropertyEvent:1.0" || repid == "IDL:ExtendedEvent/MessageEvent:1.0")
    return PortType::PropertyEvent;
  if (repid == "IDL:rsca/Command:1.0")
    return PortType::Command;
  return std::nullopt;
}

std::string_view repid_of(PortType type) {
  switch (type) {
  case PortType::Samples:
    return "IDL:rsca/SampleSeq:1.0";
  case PortType::PropertyEvent:
    return "IDL:rsca/PropertyEvent:1.0";
  case PortType::Command:
    return "IDL:rsca/Command:1.0";
  }
  return {};
}

std::string_view to_string(PortType type) {
  switch (type) {
  case PortType::Samples:
    return "SampleSeq";
  case PortType::PropertyEvent:
    return "PropertyEvent";
  case PortType::Command:
    return "Command";
  }
  return "unknown";
}

std::uint64_t now_ns() {
  const auto since_epoch = std::chrono::system_clock::now().time_since_epoch();
  return static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(since_epoch).count());
}

} // namespace rsca::port
