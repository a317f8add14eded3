#include "common/units.hpp"

#include <catch2/catch.hpp>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <utility>

#include "common/env_duration.hpp"

using namespace rsca;
using namespace std::chrono_literals;

namespace {

// The finite duration parse_duration gives, in nanoseconds.
std::int64_t duration_ns(std::string_view text) {
  INFO("duration \"" << text << "\"");
  const auto result = parse_duration(text);
  if (!result)
    FAIL("unexpected error: " << result.error());
  REQUIRE_FALSE(result->infinite());
  return result->value->count();
}

std::uint64_t size_bytes(std::string_view text) {
  INFO("size \"" << text << "\"");
  const auto result = parse_size_bytes(text);
  if (!result)
    FAIL("unexpected error: " << result.error());
  return *result;
}

double bitrate_bps(std::string_view text) {
  INFO("bit rate \"" << text << "\"");
  const auto result = parse_bitrate_bps(text);
  if (!result)
    FAIL("unexpected error: " << result.error());
  return *result;
}

// The error a parser gives for `text`, failing the test when it accepts it.
template <typename Parse>
std::string error_of(Parse parse, std::string_view text) {
  INFO("text \"" << text << "\"");
  const auto result = parse(text);
  if (result)
    FAIL("accepted, but should not have been");
  return result.error();
}

Duration finite(std::chrono::nanoseconds ns) {
  return Duration{ns};
}

} // namespace

TEST_CASE("durations in every unit", "[units][duration]") {
  CHECK(duration_ns("250ns") == 250);
  CHECK(duration_ns("500us") == 500'000);
  CHECK(duration_ns("10ms") == 10'000'000);
  CHECK(duration_ns("2s") == 2'000'000'000);
  CHECK(duration_ns("0ms") == 0);
  CHECK(duration_ns("1.5s") == 1'500'000'000);
  CHECK(duration_ns("0.25ms") == 250'000);
  CHECK(duration_ns("100ms") == 100'000'000);
}

TEST_CASE("infinite is a duration without a value", "[units][duration]") {
  const auto infinite = parse_duration("infinite");
  REQUIRE(infinite.has_value());
  CHECK(infinite->infinite());
  CHECK_FALSE(infinite->value.has_value());
  CHECK(*infinite != finite(0ns));
  CHECK_FALSE(parse_duration("10ms")->infinite());
}

TEST_CASE("malformed durations are rejected", "[units][duration]") {
  for (std::string_view text :
       {"",         "10",       "ms",       "10 ms", " 10ms", "10ms ",  "10MS",
        "10Ms",     "-5ms",     "+5ms",     "1e3ms", "10min", "10h",    "10m",
        "Infinite", "INFINITE", "infinity", "infms", "nanms", "0x10ms", "1,5ms"})
    CHECK_FALSE(error_of(parse_duration, text).empty());
  CHECK_THAT(error_of(parse_duration, "10min"),
             Catch::Matchers::Contains("no valid duration unit") &&
                 Catch::Matchers::Contains("ns, us, ms, s"));
  CHECK_THAT(error_of(parse_duration, "ms"), Catch::Matchers::Contains("is not a duration"));
}

TEST_CASE("sizes in binary and decimal units", "[units][size]") {
  CHECK(size_bytes("0B") == 0);
  CHECK(size_bytes("512B") == 512);
  CHECK(size_bytes("1KiB") == 1024);
  CHECK(size_bytes("64MiB") == 67'108'864);
  CHECK(size_bytes("32MiB") == 33'554'432);
  CHECK(size_bytes("2GiB") == 2'147'483'648ULL);
  CHECK(size_bytes("2kB") == 2'000);
  CHECK(size_bytes("3MB") == 3'000'000);
  CHECK(size_bytes("1.5GB") == 1'500'000'000);
  CHECK(size_bytes("0.5KiB") == 512);
}

TEST_CASE("malformed sizes are rejected", "[units][size]") {
  for (std::string_view text : {"", "10", "B", "KiB", "10 B", "10KB", "10kiB", "10mb", "10Mb",
                                "10MBps", "-1B", "1e3B", "10TB", "10b"})
    CHECK_FALSE(error_of(parse_size_bytes, text).empty());
  CHECK_THAT(error_of(parse_size_bytes, "10KB"),
             Catch::Matchers::Contains("no valid size unit") && Catch::Matchers::Contains("KiB"));
}

TEST_CASE("bit rates in decimal units", "[units][bitrate]") {
  CHECK(bitrate_bps("9600bps") == 9'600.0);
  CHECK(bitrate_bps("1.5kbps") == 1'500.0);
  CHECK(bitrate_bps("10Mbps") == 10'000'000.0);
  CHECK(bitrate_bps("1Gbps") == 1'000'000'000.0);
  CHECK(bitrate_bps("0bps") == 0.0);
}

TEST_CASE("malformed bit rates are rejected", "[units][bitrate]") {
  for (std::string_view text : {"", "10", "bps", "10 Mbps", "10MBps", "10mbps", "10Mb", "10Kbps",
                                "-1bps", "1e3bps", "10Tbps", "10B"})
    CHECK_FALSE(error_of(parse_bitrate_bps, text).empty());
  CHECK_THAT(error_of(parse_bitrate_bps, "10MBps"),
             Catch::Matchers::Contains("no valid bit rate unit") &&
                 Catch::Matchers::Contains("Mbps"));
}

TEST_CASE("durations print in the largest exact unit", "[units][duration][format]") {
  CHECK(format_duration(Duration{}) == "infinite");
  CHECK(format_duration(finite(2s)) == "2s");
  CHECK(format_duration(finite(1500ms)) == "1500ms");
  CHECK(format_duration(finite(10ms)) == "10ms");
  CHECK(format_duration(finite(500us)) == "500us");
  CHECK(format_duration(finite(250ns)) == "250ns");
  CHECK(format_duration(finite(1'000'001ns)) == "1000001ns");
}

TEST_CASE("durations survive a format/parse round trip", "[units][duration][format]") {
  for (std::string_view text :
       {"infinite", "0ns", "1ns", "250ns", "500us", "10ms", "1.5s", "0.001ms", "20ms", "3600s"}) {
    INFO("duration \"" << text << "\"");
    const auto parsed = parse_duration(text);
    REQUIRE(parsed.has_value());
    const auto again = parse_duration(format_duration(*parsed));
    REQUIRE(again.has_value());
    CHECK(*again == *parsed);
  }
}

TEST_CASE("sizes print in the largest exact binary unit", "[units][size][format]") {
  CHECK(format_size(0) == "0B");
  CHECK(format_size(512) == "512B");
  CHECK(format_size(1024) == "1KiB");
  CHECK(format_size(1536) == "1536B");
  CHECK(format_size(33'554'432) == "32MiB");
  CHECK(format_size(1024ULL * 1536) == "1536KiB");
  CHECK(format_size(1'500'000'000) == "1500000000B");
  for (std::uint64_t bytes : {0ULL, 1ULL, 1000ULL, 4096ULL, 33'554'432ULL, 1'500'000'000ULL}) {
    INFO(bytes << " bytes");
    CHECK(parse_size_bytes(format_size(bytes)) == bytes);
  }
}

TEST_CASE("bit rates print in the largest unit above one", "[units][bitrate][format]") {
  CHECK(format_bitrate(500) == "500bps");
  CHECK(format_bitrate(1'500) == "1.5kbps");
  CHECK(format_bitrate(9'600) == "9.6kbps");
  CHECK(format_bitrate(10'000'000) == "10Mbps");
  CHECK(format_bitrate(1e9) == "1Gbps");
  CHECK(format_bitrate(1234567) == "1.234567Mbps");
  for (double bps : {0.0, 9'600.0, 1'500.0, 10'000'000.0, 2.5e6, 1e9}) {
    INFO(bps << " bps");
    CHECK(parse_bitrate_bps(format_bitrate(bps)) == bps);
  }
}

TEST_CASE("durations and sizes too large for 64 bits are rejected", "[units]") {
  CHECK_FALSE(parse_duration("99999999999s").has_value());
  CHECK_FALSE(parse_duration("9300000000s").has_value());
  CHECK_FALSE(parse_size_bytes("99999999999GiB").has_value());
}

TEST_CASE("numbers outside the documented grammar are rejected", "[units]") {
  CHECK_FALSE(parse_duration(".5ms").has_value());
  CHECK_FALSE(parse_duration("5.ms").has_value());
  CHECK_FALSE(parse_duration("-0ms").has_value());
  CHECK_FALSE(parse_size_bytes(".5KiB").has_value());
}

TEST_CASE("a duration from the environment: a whole number of microseconds, else the fallback",
          "[units]") {
  using std::chrono::microseconds;
  const char *name = "RSCA_TEST_ENV_DURATION_US";
  ::unsetenv(name);
  CHECK(rsca::microseconds_from_env(name, microseconds{50}) == microseconds{50});
  for (const auto &[text, expected] : {std::pair{"", 50}, std::pair{"200", 200}, std::pair{"0", 0},
                                       std::pair{"-3", 50}, std::pair{"12us", 50}}) {
    ::setenv(name, text, 1);
    INFO(text);
    CHECK(rsca::microseconds_from_env(name, microseconds{50}) == microseconds{expected});
  }
  ::unsetenv(name);
}
