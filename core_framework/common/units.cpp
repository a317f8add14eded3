#include "common/units.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <utility>

#include <fmt/format.h>

namespace rsca {
namespace {

struct Unit {
  std::string_view suffix;
  double scale;
};

bool is_digit(char c) {
  return c >= '0' && c <= '9';
}

// The length of the number at the start of `text` in the documented form, digits with an
// optional fraction ("12", "12.5"; not ".5", "5." or a sign), or 0 when there is none.
std::size_t number_length(std::string_view text) {
  std::size_t i = 0;
  while (i < text.size() && is_digit(text[i]))
    ++i;
  if (i == 0 || i == text.size() || text[i] != '.')
    return i;
  std::size_t fraction = i + 1;
  while (fraction < text.size() && is_digit(text[fraction]))
    ++fraction;
  return fraction == i + 1 ? 0 : fraction;
}

// Splits "12.5ms" into 12.5 and the unit from `units` that matches the rest exactly.
template <std::size_t N>
tl::expected<std::pair<double, double>, std::string>
parse_quantity(std::string_view text, const std::array<Unit, N> &units, std::string_view what) {
  const std::size_t length = number_length(text);
  double number = 0;
  auto [end, ec] =
      std::from_chars(text.data(), text.data() + length, number, std::chars_format::fixed);
  if (length == 0 || ec != std::errc() || end != text.data() + length)
    return tl::unexpected(
        fmt::format("\"{}\" is not a {}: expected a number and a unit", text, what));
  std::string_view suffix = text.substr(length);
  for (const auto &unit : units)
    if (unit.suffix == suffix)
      return std::pair{number, unit.scale};
  std::string known;
  for (const auto &unit : units)
    known += (known.empty() ? "" : ", ") + std::string(unit.suffix);
  return tl::unexpected(
      fmt::format("\"{}\" has no valid {} unit: expected one of {}", text, what, known));
}

constexpr std::array<Unit, 4> kTimeUnits{{{"ns", 1}, {"us", 1e3}, {"ms", 1e6}, {"s", 1e9}}};
constexpr std::array<Unit, 7> kSizeUnits{{{"B", 1},
                                          {"kB", 1e3},
                                          {"MB", 1e6},
                                          {"GB", 1e9},
                                          {"KiB", 1024.0},
                                          {"MiB", 1024.0 * 1024},
                                          {"GiB", 1024.0 * 1024 * 1024}}};
constexpr std::array<Unit, 4> kRateUnits{{{"bps", 1}, {"kbps", 1e3}, {"Mbps", 1e6}, {"Gbps", 1e9}}};

} // namespace

tl::expected<Duration, std::string> parse_duration(std::string_view text) {
  if (text == "infinite")
    return Duration{};
  auto quantity = parse_quantity(text, kTimeUnits, "duration");
  if (!quantity)
    return tl::unexpected(quantity.error());
  const double ns = quantity->first * quantity->second;
  // 2^63 ns is about 292 years; anything longer is a mistake, not a period.
  if (ns >= 0x1p63)
    return tl::unexpected(
        fmt::format("\"{}\" is too long a duration (at most about 292 years)", text));
  return Duration{std::chrono::nanoseconds(std::llround(ns))};
}

tl::expected<std::uint64_t, std::string> parse_size_bytes(std::string_view text) {
  auto quantity = parse_quantity(text, kSizeUnits, "size");
  if (!quantity)
    return tl::unexpected(quantity.error());
  const double bytes = quantity->first * quantity->second;
  if (bytes >= 0x1p63)
    return tl::unexpected(fmt::format("\"{}\" is too large a size (at most 8 EiB)", text));
  return static_cast<std::uint64_t>(std::llround(bytes));
}

tl::expected<double, std::string> parse_bitrate_bps(std::string_view text) {
  auto quantity = parse_quantity(text, kRateUnits, "bit rate");
  if (!quantity)
    return tl::unexpected(quantity.error());
  return quantity->first * quantity->second;
}

std::string format_duration(const Duration &duration) {
  if (duration.infinite())
    return "infinite";
  auto ns = duration.value->count();
  if (ns % 1'000'000'000 == 0)
    return fmt::format("{}s", ns / 1'000'000'000);
  if (ns % 1'000'000 == 0)
    return fmt::format("{}ms", ns / 1'000'000);
  if (ns % 1'000 == 0)
    return fmt::format("{}us", ns / 1'000);
  return fmt::format("{}ns", ns);
}

std::string format_size(std::uint64_t bytes) {
  constexpr std::uint64_t kMiB = 1024 * 1024;
  if (bytes >= kMiB && bytes % kMiB == 0)
    return fmt::format("{}MiB", bytes / kMiB);
  if (bytes >= 1024 && bytes % 1024 == 0)
    return fmt::format("{}KiB", bytes / 1024);
  return fmt::format("{}B", bytes);
}

// Shortest text that parses back to the same value, in the largest unit that keeps it plain.
std::string format_bitrate(double bits_per_second) {
  for (const auto &unit : {kRateUnits[3], kRateUnits[2], kRateUnits[1]}) {
    if (bits_per_second >= unit.scale) {
      std::string text = fmt::format("{}{}", bits_per_second / unit.scale, unit.suffix);
      auto back = parse_bitrate_bps(text);
      if (back && *back == bits_per_second)
        return text;
    }
  }
  return fmt::format("{}bps", bits_per_second);
}

} // namespace rsca
