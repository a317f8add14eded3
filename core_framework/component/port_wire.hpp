// Private to the component runtime: the C types idlc generates from dds/ports.idl, and their
// conversion to and from the C++ port values. Writing borrows the value's buffers (no copy, no
// allocation); reading fills a value whose buffers are reused from sample to sample.
#pragma once

#include <memory>

#include "component/port_types.hpp"
#include "ports.h" // generated from dds/ports.idl

namespace rsca::port::wire {

template <typename T>
struct Traits;

template <>
struct Traits<Samples> {
  using C = rsca_port_SampleSeq;
  static const dds_topic_descriptor_t *descriptor() { return &rsca_port_SampleSeq_desc; }
};
template <>
struct Traits<PropertyEvent> {
  using C = rsca_port_PropertyEvent;
  static const dds_topic_descriptor_t *descriptor() { return &rsca_port_PropertyEvent_desc; }
};
template <>
struct Traits<Command> {
  using C = rsca_port_Command;
  static const dds_topic_descriptor_t *descriptor() { return &rsca_port_Command_desc; }
};

inline const dds_topic_descriptor_t *descriptor(PortType type) {
  switch (type) {
  case PortType::Samples:
    return Traits<Samples>::descriptor();
  case PortType::PropertyEvent:
    return Traits<PropertyEvent>::descriptor();
  case PortType::Command:
    return Traits<Command>::descriptor();
  }
  return nullptr;
}

// One `Of<T>` for the value type T that `type` carries, as a `Base`: a conversion per port type
// (component/record_relay.hpp, component/sample_view.hpp).
template <typename Base, template <typename> class Of>
std::unique_ptr<Base> make_for(PortType type) {
  switch (type) {
  case PortType::Samples:
    return std::make_unique<Of<Samples>>();
  case PortType::PropertyEvent:
    return std::make_unique<Of<PropertyEvent>>();
  case PortType::Command:
    return std::make_unique<Of<Command>>();
  }
  return nullptr;
}

// The C API takes non-const pointers but only reads what it writes.
inline char *borrow(const std::string &text) {
  return const_cast<char *>(text.c_str());
}

inline dds_sequence_double borrow(const std::vector<double> &values) {
  dds_sequence_double s{};
  s._maximum = static_cast<std::uint32_t>(values.size());
  s._length = s._maximum;
  s._buffer = const_cast<double *>(values.data());
  s._release = false;
  return s;
}

inline void assign(std::string &to, const char *from) {
  if (from == nullptr)
    to.clear();
  else
    to.assign(from);
}

inline void assign(std::vector<double> &to, const dds_sequence_double &from) {
  if (from._buffer == nullptr)
    to.clear();
  else
    to.assign(from._buffer, from._buffer + from._length);
}

inline rsca_port_SampleSeq to_wire(const Samples &v) {
  rsca_port_SampleSeq w{};
  w.timestamp_ns = v.timestamp_ns;
  w.sequence = v.sequence;
  w.stream_id = borrow(v.stream_id);
  w.sample_rate = v.sample_rate;
  w.complex = v.complex;
  w.end_of_stream = v.end_of_stream;
  w.samples = borrow(v.samples);
  return w;
}

inline void from_wire(const rsca_port_SampleSeq &w, Samples &v) {
  v.timestamp_ns = w.timestamp_ns;
  v.sequence = w.sequence;
  assign(v.stream_id, w.stream_id);
  v.sample_rate = w.sample_rate;
  v.complex = w.complex;
  v.end_of_stream = w.end_of_stream;
  assign(v.samples, w.samples);
}

inline rsca_port_PropertyEvent to_wire(const PropertyEvent &v) {
  rsca_port_PropertyEvent w{};
  w.timestamp_ns = v.timestamp_ns;
  w.source = borrow(v.source);
  w.id = borrow(v.id);
  w.value = borrow(v.value);
  return w;
}

inline void from_wire(const rsca_port_PropertyEvent &w, PropertyEvent &v) {
  v.timestamp_ns = w.timestamp_ns;
  assign(v.source, w.source);
  assign(v.id, w.id);
  assign(v.value, w.value);
}

inline rsca_port_Command to_wire(const Command &v) {
  rsca_port_Command w{};
  w.timestamp_ns = v.timestamp_ns;
  w.sequence = v.sequence;
  w.source = borrow(v.source);
  w.name = borrow(v.name);
  w.args = borrow(v.args);
  w.text = borrow(v.text);
  return w;
}

inline void from_wire(const rsca_port_Command &w, Command &v) {
  v.timestamp_ns = w.timestamp_ns;
  v.sequence = w.sequence;
  assign(v.source, w.source);
  assign(v.name, w.name);
  assign(v.args, w.args);
  assign(v.text, w.text);
}

} // namespace rsca::port::wire
