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

// Splits "12.5ms" into 12.5 and the unit from `units` that matches the rest exactly.
template <std::size_t N>
tl::expected<std::pair<double, double>, std::string>
parse_quantity(std::string_view text, const std::array<Unit, N> &units, std::string_view what) {
  double number = 0;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), number,
                                   std::chars_format::fixed);
  if (ec != std::errc() || end == text.data() || number < 0 || !std::isfinite(number))
    return tl::unexpected(fmt::format("\"{}\" is not a {}: expected a number and a unit", text, what));
  std::string_view suffix(end, static_cast<std::size_t>(text.data() + text.size() - end));
  for (const auto &unit : units)
    if (unit.suffix == suffix)
      return std::pair{number, unit.scale};
  std::string known;
  for (const auto &unit : units)
    known += (known.empty() ? "" : ", ") + std::string(unit.suffix);
  return tl::unexpected(fmt::format("\"{}\" has no valid {} unit: expected one of {}", text, what, known));
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
  auto ns = std::llround(quantity->first * quantity->second);
  return Duration{std::chrono::nanoseconds(ns)};
}

tl::expected<std::uint64_t, std::string> parse_size_bytes(std::string_view text) {
  auto quantity = parse_quantity(text, kSizeUnits, "size");
  if (!quantity)
    return tl::unexpected(quantity.error());
  return static_cast<std::uint64_t>(std::llround(quantity->first * quantity->second));
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

std::string format_bitrate(double bits_per_second) {
  if (bits_per_second >= 1e6)
    return fmt::format("{:g}Mbps", bits_per_second / 1e6);
  if (bits_per_second >= 1e3)
    return fmt::format("{:g}kbps", bits_per_second / 1e3);
  return fmt::format("{:g}bps", bits_per_second);
}

} // namespace rsca
