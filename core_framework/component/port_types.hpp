// What data ports carry: C++ values of the three IDL types of dds/ports.idl, and which repid
// (the SCD's port interface) maps to which of them.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rsca::port {

// rsca::port::SampleSeq: timestamped numeric samples with the metadata of their stream.
struct Samples {
  std::uint64_t timestamp_ns = 0; // when the first sample was taken (CLOCK_REALTIME)
  std::uint64_t sequence = 0;     // per writer, from 0
  std::string stream_id;
  double sample_rate = 0; // samples per second; 0 when not periodic
  bool complex = false;   // samples hold re, im pairs
  bool end_of_stream = false;
  std::vector<double> samples;
};

// rsca::port::PropertyEvent: a property change or event, its value as JSON text.
struct PropertyEvent {
  std::uint64_t timestamp_ns = 0;
  std::string source; // the component instance that sent it
  std::string id;
  std::string value; // JSON
};

// rsca::port::Command: a name with numeric arguments and optional text.
struct Command {
  std::uint64_t timestamp_ns = 0;
  std::uint64_t sequence = 0;
  std::string source;
  std::string name;
  std::vector<double> args;
  std::string text;
};

enum class PortType : std::uint8_t { Samples, PropertyEvent, Command };

// IDL:rsca/SampleSeq:1.0 and REDHAWK's IDL:BULKIO/data*:1.0 carry Samples;
// IDL:rsca/PropertyEvent:1.0 and IDL:ExtendedEvent/MessageEvent:1.0 carry PropertyEvent;
// IDL:rsca/Command:1.0 carries Command. Empty for any other repid.
std::optional<PortType> port_type_for_repid(std::string_view repid);
// The rsca repid of a type, e.g. "IDL:rsca/SampleSeq:1.0".
std::string_view repid_of(PortType type);
std::string_view to_string(PortType type);

template <typename T>
struct PortTypeOf;
template <>
struct PortTypeOf<Samples> {
  static constexpr PortType value = PortType::Samples;
};
template <>
struct PortTypeOf<PropertyEvent> {
  static constexpr PortType value = PortType::PropertyEvent;
};
template <>
struct PortTypeOf<Command> {
  static constexpr PortType value = PortType::Command;
};

// Now on CLOCK_REALTIME in nanoseconds: the clock of every timestamp_ns.
std::uint64_t now_ns();

} // namespace rsca::port
