// Complex property values (REDHAWK's complex="true"): "a+jb", "a-jb", "a" or "jb" over any
// numeric base type, or boolean and char as REDHAWK's complexBoolean (parts 0 or 1, or true or
// false) and complexChar (parts -128 to 127), each part checked against the base type and held
// exactly in a double (an integer part a double cannot hold is refused), and printed so that it
// reads back the same.
#include "profile/property_value_impl.hpp"

#include <cmath>

namespace rsca::profile::detail {

namespace {

bool can_be_complex(SimpleType type) {
  return is_numeric(type) || type == SimpleType::Boolean || type == SimpleType::Char;
}

// Whether a double holds `value` exactly, so that printing the complex value gives it back.
template <class T>
bool exact_in_double(T value) {
  const auto as_double = static_cast<double>(value);
  if (as_double >= std::ldexp(1.0, std::numeric_limits<T>::digits))
    return false;
  return static_cast<T>(as_double) == value;
}

template <class T>
tl::expected<double, std::string> integer_part(SimpleType type, std::string_view text) {
  const auto value = parse_integer<T>(type, text);
  if (!value)
    return tl::unexpected(value.error());
  if (!exact_in_double(*value))
    return tl::unexpected(quoted(text) + " cannot be held exactly in a complex " + type_name(type));
  return static_cast<double>(*value);
}

template <class T>
tl::expected<double, std::string> floating_part(SimpleType type, std::string_view text) {
  return parse_floating<T>(type, text).map([](T value) { return static_cast<double>(value); });
}

tl::expected<double, std::string> boolean_part(std::string_view text) {
  if (text.starts_with('+'))
    text.remove_prefix(1); // the sign split_complex leaves on an imaginary part
  if (text == "0" || text == "false")
    return 0.0;
  if (text == "1" || text == "true")
    return 1.0;
  return tl::unexpected(quoted(text) + " is not a complex boolean part (0, 1, true or false)");
}

tl::expected<double, std::string> parse_part(SimpleType type, std::string_view text) {
  switch (type) {
  case SimpleType::Boolean:
    return boolean_part(text);
  case SimpleType::Char:
    return integer_part<std::int8_t>(type, text);
  case SimpleType::Octet:
    return integer_part<std::uint8_t>(type, text);
  case SimpleType::Short:
    return integer_part<std::int16_t>(type, text);
  case SimpleType::UShort:
    return integer_part<std::uint16_t>(type, text);
  case SimpleType::Long:
    return integer_part<std::int32_t>(type, text);
  case SimpleType::ULong:
    return integer_part<std::uint32_t>(type, text);
  case SimpleType::LongLong:
    return integer_part<std::int64_t>(type, text);
  case SimpleType::ULongLong:
    return integer_part<std::uint64_t>(type, text);
  case SimpleType::Float:
    return floating_part<float>(type, text);
  case SimpleType::Double:
    return floating_part<double>(type, text);
  default:
    return tl::unexpected(type_name(type) + " cannot be complex");
  }
}

struct ComplexText {
  std::string real = "0";
  std::string imaginary = "0";
};

// Splits REDHAWK's "a+jb", "a-jb", "a", "jb" (and "-jb") into the texts of the two parts; the
// sign before 'j' goes to the imaginary part.
std::optional<ComplexText> split_complex(std::string_view text) {
  const auto j = text.find('j');
  if (j == std::string_view::npos)
    return ComplexText{std::string(text), "0"};
  if (j == 0)
    return ComplexText{"0", std::string(text.substr(1))};
  const char sign = text[j - 1];
  if (sign != '+' && sign != '-')
    return std::nullopt;
  ComplexText parts;
  if (j > 1)
    parts.real = std::string(text.substr(0, j - 1));
  parts.imaginary = sign + std::string(text.substr(j + 1));
  return parts;
}

} // namespace

ScalarResult parse_complex(SimpleType type, std::string_view text) {
  if (!can_be_complex(type))
    return tl::unexpected(type_name(type) + " cannot be complex");
  const auto invalid = [&](const std::string &why) {
    return tl::unexpected(quoted(text) + " is not a valid complex " + type_name(type) + why);
  };
  const auto parts = split_complex(text);
  if (!parts)
    return invalid(" (a+jb, a-jb, a or jb)");
  const auto real = parse_part(type, parts->real);
  if (!real)
    return invalid(": " + real.error());
  const auto imaginary = parse_part(type, parts->imaginary);
  if (!imaginary)
    return invalid(": " + imaginary.error());
  return Scalar{std::in_place_type<std::complex<double>>, *real, *imaginary};
}

namespace {

// A complex part: whole numbers in plain digits (so integer types read them back), others in
// their shortest round-trip form.
std::string format_part(double value) {
  const bool whole = std::isfinite(value) && std::trunc(value) == value;
  if (whole && std::fabs(value) < std::ldexp(1.0, 64))
    return fixed_text(value);
  return number_text(value);
}

} // namespace

std::string format_complex(const std::complex<double> &value) {
  const double imaginary = value.imag();
  const char sign = std::signbit(imaginary) ? '-' : '+';
  return format_part(value.real()) + sign + 'j' + format_part(std::fabs(imaginary));
}

} // namespace rsca::profile::detail
