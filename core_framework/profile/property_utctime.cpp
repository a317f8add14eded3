// REDHAWK's utctime, "YYYY:MM:DD::HH:MM:SS.ffffff" or "now": strict parsing with the field that
// is out of range named, printing that round-trips, and the proleptic Gregorian calendar
// arithmetic between dates and days since 1970 that both need (no time zone, no leap seconds,
// no dependence on the C library's time functions).
#include "profile/property_value_impl.hpp"

#include <algorithm>
#include <array>

namespace rsca::profile::detail {

namespace {

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

constexpr std::string_view kUtcForm = "YYYY:MM:DD::HH:MM:SS[.ffffff] or now";

unsigned read_digits(std::string_view text) {
  unsigned value = 0;
  for (const char c : text)
    value = value * 10 + static_cast<unsigned>(c - '0');
  return value;
}

// The six numbers of "YYYY:MM:DD::HH:MM:SS" and what follows them (the fraction). The year has
// four digits; the others one or two, as REDHAWK writes "2017:2:1::12:01:00" too.
struct UtcFields {
  std::array<unsigned, 6> numbers{};
  std::string_view rest;
};

std::optional<UtcFields> split_utc_fields(std::string_view text) {
  constexpr std::string_view kSeparators[] = {":", ":", "::", ":", ":", ""};
  UtcFields fields;
  for (std::size_t i = 0; i < fields.numbers.size(); ++i) {
    std::size_t digits = 0;
    while (digits < text.size() && is_digit(text[digits]))
      ++digits;
    const bool width_ok = i == 0 ? digits == 4 : (digits == 1 || digits == 2);
    if (!width_ok)
      return std::nullopt;
    fields.numbers[i] = read_digits(text.substr(0, digits));
    text.remove_prefix(digits);
    if (!text.starts_with(kSeparators[i]))
      return std::nullopt;
    text.remove_prefix(kSeparators[i].size());
  }
  fields.rest = text;
  return fields;
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

} // namespace

tl::expected<UtcTime, std::string> parse_utctime(std::string_view text) {
  if (text == "now")
    return UtcTime{true, 0, 0};
  const auto invalid = [&](const std::string &why) {
    return tl::unexpected(quoted(text) + " is not a valid utctime " + why);
  };
  const auto parts = split_utc_fields(text);
  const auto micros = parts ? read_fraction(parts->rest) : std::nullopt;
  if (!micros)
    return invalid("(" + std::string(kUtcForm) + ")");
  const auto &n = parts->numbers;
  const std::int64_t year = n[0];
  const unsigned month = n[1];
  const bool month_ok = month >= 1 && month <= 12;
  const std::array<Field, 5> fields{{
      {"month", month, 1, 12},
      {"day", n[2], 1, month_ok ? days_in_month(year, month) : 31},
      {"hour", n[3], 0, 23},
      {"minute", n[4], 0, 59},
      {"second", n[5], 0, 59},
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

} // namespace rsca::profile::detail
