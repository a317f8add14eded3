#include "profile/property_value.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <system_error>
#include <type_traits>
#include <utility>

namespace rsca::profile {
namespace {

using ScalarResult = tl::expected<Scalar, std::string>;

constexpr std::array<std::pair<SimpleType, std::string_view>, 14> kTypeNames{{
    {SimpleType::Boolean, "boolean"},
    {SimpleType::Char, "char"},
    {SimpleType::Octet, "octet"},
    {SimpleType::Short, "short"},
    {SimpleType::UShort, "ushort"},
    {SimpleType::Long, "long"},
    {SimpleType::ULong, "ulong"},
    {SimpleType::LongLong, "longlong"},
    {SimpleType::ULongLong, "ulonglong"},
    {SimpleType::Float, "float"},
    {SimpleType::Double, "double"},
    {SimpleType::String, "string"},
    {SimpleType::ObjRef, "objref"},
    {SimpleType::UtcTime, "utctime"},
}};

constexpr std::array<std::pair<Action, std::string_view>, 7> kActionNames{{
    {Action::Eq, "eq"},
    {Action::Ne, "ne"},
    {Action::Gt, "gt"},
    {Action::Lt, "lt"},
    {Action::Ge, "ge"},
    {Action::Le, "le"},
    {Action::External, "external"},
}};

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

// Integers in decimal; floating values in their shortest round-trip form.
template <class T>
std::string number_text(T value) {
  std::array<char, 64> buffer{};
  const auto [end, ec] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  if (ec != std::errc{})
    return {};
  return std::string(buffer.data(), end);
}

// A whole number written out in digits (shortest fixed notation), never in exponent form.
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

struct Magnitude {
  bool negative = false;
  std::uint64_t value = 0;
};

enum class IntegerProblem : std::uint8_t { Malformed, TooLarge };

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

// from_chars found the decimal `text` out of range: whether it is too close to zero rather than
// too large.
bool is_underflow(std::string_view text) {
  if (!text.empty() && text.front() == '-')
    text.remove_prefix(1);
  const auto e = text.find_first_of("eE");
  const auto exponent = e == std::string_view::npos ? std::string_view{} : text.substr(e + 1);
  return decimal_order(text.substr(0, e)) + read_exponent(exponent) < 0;
}

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

// ---------------------------------------------------------------------------------------------
// utctime

bool is_leap_year(std::int64_t year) {
  return (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
}

unsigned days_in_month(std::int64_t year, unsigned month) {
  constexpr std::array<unsigned, 12> kDays{31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  if (month == 2 && is_leap_year(year))
    return 29;
  return kDays.at(month - 1);
}

// Counting years from March puts each leap day last in its year, so the day of the year follows
// from the month by one linear formula. 400 Gregorian years (an "era") are exactly 146097 days.
constexpr std::int64_t kDaysPerEra = 146097;
// Days from 0000-03-01 to 1970-01-01.
constexpr std::int64_t kEpochFromMarchZero = 719468;

std::int64_t floor_div(std::int64_t value, std::int64_t divisor) {
  const std::int64_t quotient = value / divisor;
  return (value % divisor != 0 && value < 0) ? quotient - 1 : quotient;
}

unsigned day_of_march_year(unsigned month, unsigned day) {
  const unsigned month_from_march = month > 2 ? month - 3 : month + 9;
  return (153 * month_from_march + 2) / 5 + day - 1;
}

// Days since 1970-01-01 of a proleptic Gregorian date.
std::int64_t days_from_civil(std::int64_t year, unsigned month, unsigned day) {
  const std::int64_t march_year = month <= 2 ? year - 1 : year;
  const std::int64_t era = floor_div(march_year, 400);
  const auto year_of_era = static_cast<unsigned>(march_year - era * 400);
  const unsigned day_of_era =
      year_of_era * 365 + year_of_era / 4 - year_of_era / 100 + day_of_march_year(month, day);
  return era * kDaysPerEra + day_of_era - kEpochFromMarchZero;
}

struct CivilDate {
  std::int64_t year = 1970;
  unsigned month = 1;
  unsigned day = 1;
};

// The proleptic Gregorian date `days` after 1970-01-01 (the inverse of days_from_civil).
CivilDate civil_from_days(std::int64_t days) {
  const std::int64_t from_march_zero = days + kEpochFromMarchZero;
  const std::int64_t era = floor_div(from_march_zero, kDaysPerEra);
  const auto day_of_era = static_cast<unsigned>(from_march_zero - era * kDaysPerEra);
  // Remove the leap days so far (one per 4 years, less one per 100, plus one per 400).
  const unsigned year_of_era =
      (day_of_era - day_of_era / 1460 + day_of_era / 36524 - day_of_era / 146096) / 365;
  const unsigned day_of_year =
      day_of_era - (year_of_era * 365 + year_of_era / 4 - year_of_era / 100);
  const unsigned month_from_march = (5 * day_of_year + 2) / 153;
  CivilDate date;
  date.day = day_of_year - (153 * month_from_march + 2) / 5 + 1;
  date.month = month_from_march < 10 ? month_from_march + 3 : month_from_march - 9;
  date.year = era * 400 + year_of_era + (date.month <= 2 ? 1 : 0);
  return date;
}

constexpr std::string_view kUtcLayout = "dddd:dd:dd::dd:dd:dd";
constexpr std::string_view kUtcForm = "YYYY:MM:DD::HH:MM:SS[.ffffff] or now";

bool matches_utc_layout(std::string_view text) {
  if (text.size() < kUtcLayout.size())
    return false;
  for (std::size_t i = 0; i < kUtcLayout.size(); ++i) {
    const bool ok = kUtcLayout[i] == 'd' ? is_digit(text[i]) : text[i] == kUtcLayout[i];
    if (!ok)
      return false;
  }
  return true;
}

unsigned read_digits(std::string_view text) {
  unsigned value = 0;
  for (const char c : text)
    value = value * 10 + static_cast<unsigned>(c - '0');
  return value;
}

// ".f" to ".ffffff" as microseconds; empty text is zero.
std::optional<std::uint32_t> read_fraction(std::string_view text) {
  if (text.empty())
    return 0U;
  if (text.front() != '.')
    return std::nullopt;
  const auto digits = text.substr(1);
  if (digits.empty() || digits.size() > 6 || !std::all_of(digits.begin(), digits.end(), is_digit))
    return std::nullopt;
  std::uint32_t micros = read_digits(digits);
  for (std::size_t i = digits.size(); i < 6; ++i)
    micros *= 10;
  return micros;
}

struct Field {
  std::string_view name;
  unsigned value;
  unsigned low;
  unsigned high;
};

tl::expected<UtcTime, std::string> parse_utctime(std::string_view text) {
  if (text == "now")
    return UtcTime{true, 0, 0};
  const auto invalid = [&](const std::string &why) {
    return tl::unexpected(quoted(text) + " is not a valid utctime " + why);
  };
  const auto micros =
      matches_utc_layout(text) ? read_fraction(text.substr(kUtcLayout.size())) : std::nullopt;
  if (!micros)
    return invalid("(" + std::string(kUtcForm) + ")");
  const std::int64_t year = read_digits(text.substr(0, 4));
  const unsigned month = read_digits(text.substr(5, 2));
  const bool month_ok = month >= 1 && month <= 12;
  const std::array<Field, 5> fields{{
      {"month", month, 1, 12},
      {"day", read_digits(text.substr(8, 2)), 1, month_ok ? days_in_month(year, month) : 31},
      {"hour", read_digits(text.substr(12, 2)), 0, 23},
      {"minute", read_digits(text.substr(15, 2)), 0, 59},
      {"second", read_digits(text.substr(18, 2)), 0, 59},
  }};
  for (const Field &field : fields) {
    if (field.value < field.low || field.value > field.high)
      return invalid("(" + std::string(field.name) + " " + number_text(field.value) +
                     " is out of range " + number_text(field.low) + ".." + number_text(field.high) +
                     ")");
  }
  const std::int64_t days = days_from_civil(year, month, fields[1].value);
  const std::int64_t seconds =
      days * 86400 + fields[2].value * 3600 + fields[3].value * 60 + fields[4].value;
  return UtcTime{false, seconds, *micros};
}

std::string format_utctime(const UtcTime &time) {
  if (time.now)
    return "now";
  const std::int64_t days = floor_div(time.seconds, 86400);
  const std::int64_t second_of_day = time.seconds - days * 86400;
  const CivilDate date = civil_from_days(days);
  return zero_padded(date.year, 4) + ":" + zero_padded(date.month, 2) + ":" +
         zero_padded(date.day, 2) + "::" + zero_padded(second_of_day / 3600, 2) + ":" +
         zero_padded(second_of_day / 60 % 60, 2) + ":" + zero_padded(second_of_day % 60, 2) + "." +
         zero_padded(time.micros, 6);
}

// ---------------------------------------------------------------------------------------------
// Complex

bool can_be_complex(SimpleType type) {
  return is_numeric(type);
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

tl::expected<double, std::string> parse_part(SimpleType type, std::string_view text) {
  switch (type) {
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

// A complex part: whole numbers in plain digits (so integer types read them back), others in
// their shortest round-trip form.
std::string format_part(double value) {
  const bool whole = std::isfinite(value) && std::trunc(value) == value;
  if (whole && std::fabs(value) < std::ldexp(1.0, 64))
    return fixed_text(value);
  return number_text(value);
}

std::string format_complex(const std::complex<double> &value) {
  const double imaginary = value.imag();
  const char sign = std::signbit(imaginary) ? '-' : '+';
  return format_part(value.real()) + sign + 'j' + format_part(std::fabs(imaginary));
}

// ---------------------------------------------------------------------------------------------
// Dispatch

template <class T>
ScalarResult to_scalar(tl::expected<T, std::string> parsed) {
  return std::move(parsed).map([](T value) { return Scalar{std::in_place_type<T>, value}; });
}

ScalarResult parse_simple(SimpleType type, std::string_view text) {
  switch (type) {
  case SimpleType::Boolean:
    return to_scalar(parse_boolean(text));
  case SimpleType::Char:
    return to_scalar(parse_char(text));
  case SimpleType::Octet:
    return to_scalar(parse_integer<std::uint8_t>(type, text));
  case SimpleType::Short:
    return to_scalar(parse_integer<std::int16_t>(type, text));
  case SimpleType::UShort:
    return to_scalar(parse_integer<std::uint16_t>(type, text));
  case SimpleType::Long:
    return to_scalar(parse_integer<std::int32_t>(type, text));
  case SimpleType::ULong:
    return to_scalar(parse_integer<std::uint32_t>(type, text));
  case SimpleType::LongLong:
    return to_scalar(parse_integer<std::int64_t>(type, text));
  case SimpleType::ULongLong:
    return to_scalar(parse_integer<std::uint64_t>(type, text));
  case SimpleType::Float:
    return to_scalar(parse_floating<float>(type, text));
  case SimpleType::Double:
    return to_scalar(parse_floating<double>(type, text));
  case SimpleType::String:
  case SimpleType::ObjRef:
    return Scalar{std::in_place_type<std::string>, text};
  case SimpleType::UtcTime:
    return to_scalar(parse_utctime(text));
  }
  return tl::unexpected(std::string("unknown simple type"));
}

struct Formatter {
  std::string operator()(bool value) const { return value ? "true" : "false"; }
  std::string operator()(char value) const { return std::string(1, value); }
  std::string operator()(const std::string &value) const { return value; }
  std::string operator()(const UtcTime &value) const { return format_utctime(value); }
  std::string operator()(const std::complex<double> &value) const { return format_complex(value); }
  template <class T>
  std::string operator()(T value) const {
    return number_text(value);
  }
};

template <class T>
constexpr bool kOrdered =
    std::is_arithmetic_v<T> && !std::is_same_v<T, bool> && !std::is_same_v<T, char>;

template <class T>
std::optional<bool> compare(Action action, const T &device, const T &requested) {
  switch (action) {
  case Action::Eq:
    return device == requested;
  case Action::Ne:
    return device != requested;
  default:
    break;
  }
  if constexpr (kOrdered<T>) {
    switch (action) {
    case Action::Gt:
      return device > requested;
    case Action::Lt:
      return device < requested;
    case Action::Ge:
      return device >= requested;
    case Action::Le:
      return device <= requested;
    default:
      break;
    }
  }
  return std::nullopt;
}

} // namespace

std::optional<SimpleType> simple_type_from_name(std::string_view name) {
  for (const auto &[type, type_text] : kTypeNames) {
    if (type_text == name)
      return type;
  }
  return std::nullopt;
}

std::string_view to_string(SimpleType type) {
  for (const auto &[candidate, name] : kTypeNames) {
    if (candidate == type)
      return name;
  }
  return "unknown";
}

bool is_integer(SimpleType type) {
  switch (type) {
  case SimpleType::Octet:
  case SimpleType::Short:
  case SimpleType::UShort:
  case SimpleType::Long:
  case SimpleType::ULong:
  case SimpleType::LongLong:
  case SimpleType::ULongLong:
    return true;
  default:
    return false;
  }
}

bool is_floating(SimpleType type) {
  return type == SimpleType::Float || type == SimpleType::Double;
}

bool is_numeric(SimpleType type) {
  return is_integer(type) || is_floating(type);
}

std::optional<Action> action_from_name(std::string_view name) {
  for (const auto &[action, action_text] : kActionNames) {
    if (action_text == name)
      return action;
  }
  return std::nullopt;
}

std::string_view to_string(Action action) {
  for (const auto &[candidate, name] : kActionNames) {
    if (candidate == action)
      return name;
  }
  return "unknown";
}

tl::expected<Scalar, std::string> parse_scalar(TypeSpec spec, std::string_view text) {
  const bool textual = spec.type == SimpleType::String || spec.type == SimpleType::ObjRef;
  if (spec.complex)
    return parse_complex(spec.type, trim(text));
  if (textual)
    return Scalar{std::in_place_type<std::string>, text};
  // A lone character is taken as it is, so that char can hold a space.
  if (spec.type == SimpleType::Char && text.size() == 1)
    return Scalar{std::in_place_type<char>, text.front()};
  return parse_simple(spec.type, trim(text));
}

std::string format_scalar(const Scalar &value) {
  return std::visit(Formatter{}, value);
}

std::optional<bool> satisfies(Action action, const Scalar &device_value, const Scalar &requested) {
  if (action == Action::External || device_value.index() != requested.index())
    return std::nullopt;
  return std::visit(
      [&](const auto &device) {
        using T = std::decay_t<decltype(device)>;
        return compare<T>(action, device, std::get<T>(requested));
      },
      device_value);
}

} // namespace rsca::profile
