// The quantities RSCA's profile extensions carry as text: durations ("10ms", "infinite"),
// sizes ("64MiB") and bit rates ("10Mbps").
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include <tl/expected.hpp>

namespace rsca {

// A duration; std::nullopt inside means "infinite".
struct Duration {
  std::optional<std::chrono::nanoseconds> value;
  bool infinite() const { return !value.has_value(); }
  friend bool operator==(const Duration &, const Duration &) = default;
};

tl::expected<Duration, std::string> parse_duration(std::string_view text);
tl::expected<std::uint64_t, std::string> parse_size_bytes(std::string_view text);
tl::expected<double, std::string> parse_bitrate_bps(std::string_view text);

std::string format_duration(const Duration &duration);
std::string format_size(std::uint64_t bytes);
std::string format_bitrate(double bits_per_second);

} // namespace rsca
