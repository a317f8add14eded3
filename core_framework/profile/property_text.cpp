// The text of property values: the character and number helpers every value type uses, and the
// parsing of integers, floating point, booleans and chars that does not depend on the C++ type
// (the templates over it are in property_value_impl.hpp).
#include "profile/property_value_impl.hpp"

#include <algorithm>
#include <array>
#include <charconv>

namespace rsca::profile::detail {

// ---------------------------------------------------------------------------------------------
// Text helpers

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

bool is_digit(char c) {
  return c >= '0' && c <= '9';
}

char lower(char c) {
  return c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c;
}

std::string_view trim(std::string_view text) {
  while (!text.empty() && is_space(text.front()))
    text.remove_prefix(1);
  while (!text.empty() && is_space(text.back()))
    text.remove_suffix(1);
  return text;
}

bool equals_ignoring_case(std::string_view a, std::string_view b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(),
                    [](char x, char y) { return lower(x) == lower(y); });
}

std::string quoted(std::string_view text) {
  std::string out = "\"";
  out += text;
  out += '"';
  return out;
}

std::string type_name(SimpleType type) {
  return std::string(to_string(type));
}

std::string fixed_text(double value) {
  std::array<char, 400> buffer{};
  const auto [end, ec] =
      std::to_chars(buffer.data(), buffer.data() + buffer.size(), value, std::chars_format::fixed);
  if (ec != std::errc{})
    return number_text(value);
  return std::string(buffer.data(), end);
}

std::string zero_padded(std::int64_t value, std::size_t width) {
  std::string digits = number_text(value);
  if (value < 0 || digits.size() >= width)
    return digits;
  return std::string(width - digits.size(), '0') + digits;
}

// ---------------------------------------------------------------------------------------------
// Integers

// Reads [+|-][0x]digits into a sign and a 64-bit magnitude.
tl::expected<Magnitude, IntegerProblem> read_magnitude(std::string_view text) {
  Magnitude magnitude;
  if (!text.empty() && (text.front() == '+' || text.front() == '-')) {
    magnitude.negative = text.front() == '-';
    text.remove_prefix(1);
  }
  int base = 10;
  if (text.size() >= 2 && text[0] == '0' && lower(text[1]) == 'x') {
    base = 16;
    text.remove_prefix(2);
  }
  if (text.empty())
    return tl::unexpected(IntegerProblem::Malformed);
  const char *end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, magnitude.value, base);
  if (ptr != end)
    return tl::unexpected(IntegerProblem::Malformed);
  if (ec == std::errc::result_out_of_range)
    return tl::unexpected(IntegerProblem::TooLarge);
  if (ec != std::errc{})
    return tl::unexpected(IntegerProblem::Malformed);
  return magnitude;
}

// ---------------------------------------------------------------------------------------------
// Floating point

namespace {

// The power of ten of the leading nonzero digit of a plain decimal "ddd.ddd" (0 when all zero).
std::int64_t decimal_order(std::string_view mantissa) {
  const auto point = mantissa.find('.');
  const auto integer = mantissa.substr(0, point);
  const auto first = integer.find_first_not_of('0');
  if (first != std::string_view::npos)
    return static_cast<std::int64_t>(integer.size() - first) - 1;
  if (point == std::string_view::npos)
    return 0;
  const auto lead = mantissa.substr(point + 1).find_first_not_of('0');
  return lead == std::string_view::npos ? 0 : -static_cast<std::int64_t>(lead) - 1;
}

// The value of an exponent "[+|-]digits", saturated far beyond any floating range.
std::int64_t read_exponent(std::string_view text) {
  bool negative = false;
  if (!text.empty() && (text.front() == '+' || text.front() == '-')) {
    negative = text.front() == '-';
    text.remove_prefix(1);
  }
  std::int64_t value = 0;
  for (const char c : text)
    value = std::min<std::int64_t>(value * 10 + (c - '0'), 1'000'000'000);
  return negative ? -value : value;
}

} // namespace

bool is_underflow(std::string_view text) {
  if (!text.empty() && text.front() == '-')
    text.remove_prefix(1);
  const auto e = text.find_first_of("eE");
  const auto exponent = e == std::string_view::npos ? std::string_view{} : text.substr(e + 1);
  return decimal_order(text.substr(0, e)) + read_exponent(exponent) < 0;
}

// ---------------------------------------------------------------------------------------------
// Boolean and char

tl::expected<bool, std::string> parse_boolean(std::string_view text) {
  if (text == "1" || equals_ignoring_case(text, "true"))
    return true;
  if (text == "0" || equals_ignoring_case(text, "false"))
    return false;
  return tl::unexpected(quoted(text) + " is not a boolean (true or false)");
}

tl::expected<char, std::string> parse_char(std::string_view text) {
  if (text.size() != 1)
    return tl::unexpected(quoted(text) + " is not a single character");
  return text.front();
}

} // namespace rsca::profile::detail
