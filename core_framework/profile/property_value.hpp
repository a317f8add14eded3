// Typed values of SCA properties: the scalar types a PRF can declare, strict parsing of the text a
// profile holds, printing that round-trips, and the comparisons allocation properties use.
#pragma once

#include <complex>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

#include <tl/expected.hpp>

namespace rsca::profile {

// The SCA 2.2.2 simple types plus REDHAWK's utctime.
enum class SimpleType : std::uint8_t {
  Boolean,
  Char,
  Octet,
  Short,
  UShort,
  Long,
  ULong,
  LongLong,
  ULongLong,
  Float,
  Double,
  String,
  ObjRef,
  UtcTime,
};

// The comparison an allocation property asks of a device (SCA puts the device's value on the left).
enum class Action : std::uint8_t { Eq, Ne, Gt, Lt, Ge, Le, External };

std::optional<SimpleType> simple_type_from_name(std::string_view name);
std::string_view to_string(SimpleType type);
bool is_integer(SimpleType type);
bool is_floating(SimpleType type);
bool is_numeric(SimpleType type);

std::optional<Action> action_from_name(std::string_view name);
std::string_view to_string(Action action);

// The declared type of a simple or simplesequence; `complex` is REDHAWK's complex="true".
struct TypeSpec {
  SimpleType type = SimpleType::String;
  bool complex = false;
  friend bool operator==(const TypeSpec &, const TypeSpec &) = default;
};

// REDHAWK writes utctime as "YYYY:MM:DD::HH:MM:SS.ffffff"; "now" is resolved when it is used.
struct UtcTime {
  bool now = false;
  std::int64_t seconds = 0; // since 1970-01-01T00:00:00Z
  std::uint32_t micros = 0; // fraction of the second
  friend bool operator==(const UtcTime &, const UtcTime &) = default;
};

// One value in its exact declared type. std::string carries string and objref; complex values
// of every base type are held as std::complex<double> after each part was checked against the base.
using Scalar = std::variant<bool, char, std::uint8_t, std::int16_t, std::uint16_t, std::int32_t,
                            std::uint32_t, std::int64_t, std::uint64_t, float, double, std::string,
                            UtcTime, std::complex<double>>;

// Parses `text` as a value of `spec`, strictly: the whole text, within the type's range.
// The error says what was wrong, e.g. `"70000" is out of range for short (-32768..32767)`.
tl::expected<Scalar, std::string> parse_scalar(TypeSpec spec, std::string_view text);

// Prints a value so that parse_scalar(spec, format_scalar(v)) == v.
std::string format_scalar(const Scalar &value);

// Whether a device whose property holds `device_value` satisfies a request for `requested`
// under `action` (device on the left: Gt means device_value > requested). Both must come from
// the same TypeSpec. Empty when the action does not apply: External, or an order on a
// non-numeric type.
std::optional<bool> satisfies(Action action, const Scalar &device_value, const Scalar &requested);

} // namespace rsca::profile
