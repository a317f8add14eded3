// The private parts of typed property values (profile/property_value.hpp), shared by its files:
// property_text.cpp (text helpers, integers, floating point, boolean and char),
// property_utctime.cpp (REDHAWK's utctime and the calendar arithmetic it needs),
// property_complex.cpp (complex values over every numeric base type) and property_value.cpp (type
// and action names, the dispatch by type, printing and comparing). The number parsers are templates
// over the C++ type that holds the value, so they stand here whole. Nothing outside profile/
// includes this header.
#pragma once

#include <array>
#include <charconv>
#include <complex>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>

#include <tl/expected.hpp>

#include "profile/property_value.hpp"

namespace rsca::profile::detail {

using ScalarResult = tl::expected<Scalar, std::string>;

// ---------------------------------------------------------------------------------------------
// Text helpers (property_text.cpp)

bool is_space(char c);
bool is_digit(char c);
char lower(char c);
std::string_view trim(std::string_view text);
bool equals_ignoring_case(std::string_view a, std::string_view b);
std::string quoted(std::string_view text);
std::string type_name(SimpleType type);
// A whole number written out in digits (shortest fixed notation), never in exponent form.
std::string fixed_text(double value);
std::string zero_padded(std::int64_t value, std::size_t width);

// Integers in decimal; floating values in their shortest round-trip form.
template <class T>
std::string number_text(T value) {
  std::array<char, 64> buffer{};
  const auto [end, ec] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  if (ec != std::errc{})
    return {};
  return std::string(buffer.data(), end);
}

// ---------------------------------------------------------------------------------------------
// Integers

struct Magnitude {
  bool negative = false;
  std::uint64_t value = 0;
};

enum class IntegerProblem : std::uint8_t { Malformed, TooLarge };

// Reads [+|-][0x]digits into a sign and a 64-bit magnitude (property_text.cpp).
tl::expected<Magnitude, IntegerProblem> read_magnitude(std::string_view text);

// The value of `magnitude` as a T, if T can hold it.
template <class T>
std::optional<T> fit(Magnitude magnitude) {
  constexpr auto max = static_cast<std::uint64_t>(std::numeric_limits<T>::max());
  if (!magnitude.negative)
    return magnitude.value <= max ? std::optional<T>(static_cast<T>(magnitude.value))
                                  : std::nullopt;
  if constexpr (std::is_unsigned_v<T>) {
    return std::nullopt;
  } else {
    if (magnitude.value > max + 1)
      return std::nullopt;
    if (magnitude.value == 0)
      return T{0};
    return static_cast<T>(-static_cast<std::int64_t>(magnitude.value - 1) - 1);
  }
}

template <class T>
std::string range_text() {
  return "(" + number_text(std::numeric_limits<T>::min()) + ".." +
         number_text(std::numeric_limits<T>::max()) + ")";
}

template <class T>
tl::expected<T, std::string> parse_integer(SimpleType type, std::string_view text) {
  const auto magnitude = read_magnitude(text);
  if (!magnitude && magnitude.error() == IntegerProblem::Malformed)
    return tl::unexpected(quoted(text) + " is not a valid " + type_name(type));
  if (magnitude) {
    if (const auto value = fit<T>(*magnitude))
      return *value;
    if (magnitude->negative && magnitude->value == 0)
      return tl::unexpected(quoted(text) + " is not a valid " + type_name(type) +
                            " (unsigned types take no minus sign)");
  }
  return tl::unexpected(quoted(text) + " is out of range for " + type_name(type) + " " +
                        range_text<T>());
}

// ---------------------------------------------------------------------------------------------
// Floating point

// from_chars found the decimal `text` out of range: whether it is too close to zero rather than
// too large (property_text.cpp).
bool is_underflow(std::string_view text);

// Parses decimal floating text: optional sign, exponent, "nan", "inf". Values too small for T
// round to a zero of the same sign; values too large round to an infinity of the same sign. That
// is IEEE rounding, what strtof/strtod and so REDHAWK do: REDHAWK's own agc.prf.xml gives a float
// the default 1e99 and means +inf.
template <class T>
tl::expected<T, std::string> parse_floating(SimpleType type, std::string_view text) {
  const auto invalid = [&] {
    return tl::unexpected(quoted(text) + " is not a valid " + type_name(type));
  };
  std::string_view body = text;
  if (!body.empty() && body.front() == '+') {
    body.remove_prefix(1);
    if (!body.empty() && (body.front() == '+' || body.front() == '-'))
      return invalid();
  }
  if (body.empty())
    return invalid();
  T value{};
  const char *end = body.data() + body.size();
  const auto [ptr, ec] = std::from_chars(body.data(), end, value);
  if (ptr != end)
    return invalid();
  if (ec == std::errc::result_out_of_range && is_underflow(body))
    return body.front() == '-' ? -T{0} : T{0};
  if (ec == std::errc::result_out_of_range)
    return body.front() == '-' ? -std::numeric_limits<T>::infinity()
                               : std::numeric_limits<T>::infinity();
  if (ec != std::errc{})
    return invalid();
  return value;
}

// ---------------------------------------------------------------------------------------------
// Boolean and char (property_text.cpp), utctime (property_utctime.cpp), complex
// (property_complex.cpp)

tl::expected<bool, std::string> parse_boolean(std::string_view text);
tl::expected<char, std::string> parse_char(std::string_view text);

tl::expected<UtcTime, std::string> parse_utctime(std::string_view text);
std::string format_utctime(const UtcTime &time);

// REDHAWK's "a+jb", "a-jb", "a", "jb" of a numeric base type.
ScalarResult parse_complex(SimpleType type, std::string_view text);
std::string format_complex(const std::complex<double> &value);

} // namespace rsca::profile::detail
