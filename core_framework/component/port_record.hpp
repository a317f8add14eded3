// Private to the component runtime: the port values as records of a same-host ring
// (shm/ring.hpp). Both ends are processes of one host and one build of this runtime, so a record
// is the fields in order, in the host's byte order: numbers as they are in memory, a string or a
// sequence as its length (32 bits) and then its elements. Cyclone's own serializer needs a topic,
// hence a participant, which a same-host connection exists to do without.
//
// Reading never trusts a record: every length is checked against the record's bytes (a writer
// may overwrite it while it is read; the ring then drops what was read).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "component/port_types.hpp"

namespace rsca::port::record {

class Writer {
public:
  explicit Writer(std::byte *at) : at_(at) {}
  template <typename N>
  void number(N value) {
    std::memcpy(at_, &value, sizeof(N));
    at_ += sizeof(N);
  }
  void text(const std::string &s) { span(s.data(), s.size(), 1); }
  void doubles(const std::vector<double> &v) { span(v.data(), v.size(), sizeof(double)); }

private:
  void span(const void *data, std::size_t count, std::size_t element) {
    number(static_cast<std::uint32_t>(count));
    if (count != 0)
      std::memcpy(at_, data, count * element);
    at_ += count * element;
  }
  std::byte *at_;
};

class Reader {
public:
  Reader(const std::byte *at, std::size_t bytes) : at_(at), left_(bytes) {}
  template <typename N>
  bool number(N &value) {
    if (left_ < sizeof(N))
      return false;
    std::memcpy(&value, at_, sizeof(N));
    advance(sizeof(N));
    return true;
  }
  bool flag(bool &value) {
    std::uint8_t byte = 0;
    if (!number(byte))
      return false;
    value = byte != 0;
    return true;
  }
  bool text(std::string &s) {
    std::uint32_t n = 0;
    if (!number(n) || n > left_)
      return false;
    s.assign(reinterpret_cast<const char *>(at_), n);
    advance(n);
    return true;
  }
  bool doubles(std::vector<double> &v) {
    std::uint32_t n = 0;
    if (!number(n) || n > left_ / sizeof(double))
      return false;
    v.resize(n);
    if (n != 0)
      std::memcpy(v.data(), at_, n * sizeof(double));
    advance(n * sizeof(double));
    return true;
  }

private:
  void advance(std::size_t n) {
    at_ += n;
    left_ -= n;
  }
  const std::byte *at_;
  std::size_t left_;
};

constexpr std::size_t kLength = sizeof(std::uint32_t);

inline std::size_t size_of(const Samples &v) {
  return 8 + 8 + kLength + v.stream_id.size() + 8 + 1 + 1 + kLength +
         v.samples.size() * sizeof(double);
}
inline void write(const Samples &v, Writer &w) {
  w.number(v.timestamp_ns);
  w.number(v.sequence);
  w.text(v.stream_id);
  w.number(v.sample_rate);
  w.number(static_cast<std::uint8_t>(v.complex));
  w.number(static_cast<std::uint8_t>(v.end_of_stream));
  w.doubles(v.samples);
}
inline bool read(Reader &r, Samples &v) {
  return r.number(v.timestamp_ns) && r.number(v.sequence) && r.text(v.stream_id) &&
         r.number(v.sample_rate) && r.flag(v.complex) && r.flag(v.end_of_stream) &&
         r.doubles(v.samples);
}

inline std::size_t size_of(const PropertyEvent &v) {
  return 8 + 3 * kLength + v.source.size() + v.id.size() + v.value.size();
}
inline void write(const PropertyEvent &v, Writer &w) {
  w.number(v.timestamp_ns);
  w.text(v.source);
  w.text(v.id);
  w.text(v.value);
}
inline bool read(Reader &r, PropertyEvent &v) {
  return r.number(v.timestamp_ns) && r.text(v.source) && r.text(v.id) && r.text(v.value);
}

inline std::size_t size_of(const Command &v) {
  return 8 + 8 + 4 * kLength + v.source.size() + v.name.size() + v.args.size() * sizeof(double) +
         v.text.size();
}
inline void write(const Command &v, Writer &w) {
  w.number(v.timestamp_ns);
  w.number(v.sequence);
  w.text(v.source);
  w.text(v.name);
  w.doubles(v.args);
  w.text(v.text);
}
inline bool read(Reader &r, Command &v) {
  return r.number(v.timestamp_ns) && r.number(v.sequence) && r.text(v.source) && r.text(v.name) &&
         r.doubles(v.args) && r.text(v.text);
}

} // namespace rsca::port::record
