// The content filter of event-channel subscribers: its grammar, its evaluation, its errors.
#include <map>

#include <catch2/catch.hpp>

#include "common/content_filter.hpp"

using namespace rsca;

namespace {

// An event as a map of fields.
bool matches(std::string_view expression, const std::map<std::string, FilterValue> &event) {
  auto filter = ContentFilter::parse(expression);
  INFO(expression << ": " << (filter ? "" : filter.error()));
  REQUIRE(filter.has_value());
  return filter->matches([&](std::string_view field) -> std::optional<FilterValue> {
    auto it = event.find(std::string(field));
    return it == event.end() ? std::nullopt : std::optional<FilterValue>(it->second);
  });
}

} // namespace

TEST_CASE("a filter compares fields with numbers, texts and booleans", "[filter]") {
  const std::map<std::string, FilterValue> near{
      {"range", 0.42}, {"sensor", std::string("front")}, {"valid", true}};
  CHECK(matches("range < 0.6", near));
  CHECK_FALSE(matches("range >= 0.6", near));
  CHECK(matches("range = 0.42 and sensor = 'front'", near));
  CHECK(matches("sensor == \"front\"", near));
  CHECK(matches("sensor != 'rear'", near));
  CHECK(matches("sensor <> 'rear'", near));
  CHECK(matches("valid", near)); // a bare field is a condition
  CHECK(matches("valid = true", near));
  CHECK_FALSE(matches("not valid", near));
  CHECK(matches("range < 10.0 && valid", near));
  CHECK(matches("range > 1 || sensor = 'front'", near));
  CHECK_FALSE(matches("!(range < 1)", near));
}

TEST_CASE("a filter's precedence: not, then and, then or", "[filter]") {
  const std::map<std::string, FilterValue> e{{"a", 1.0}, {"b", 2.0}, {"c", 3.0}};
  // a = 0 or (b = 2 and c = 3)
  CHECK(matches("a = 0 or b = 2 and c = 3", e));
  // (a = 0 or b = 2) and c = 0
  CHECK_FALSE(matches("(a = 0 or b = 2) and c = 0", e));
  CHECK(matches("not a = 0 and b = 2", e));
}

TEST_CASE("a missing field or a comparison across types is false", "[filter]") {
  const std::map<std::string, FilterValue> e{{"range", 0.5}, {"name", std::string("x")}};
  CHECK_FALSE(matches("speed > 1", e));
  CHECK(matches("not speed > 1", e));
  CHECK_FALSE(matches("name > 1", e));
  CHECK_FALSE(matches("range = 'x'", e));
}

TEST_CASE("a malformed filter says where and what was expected", "[filter]") {
  auto error = [](std::string_view expression) {
    auto filter = ContentFilter::parse(expression);
    REQUIRE_FALSE(filter.has_value());
    return filter.error();
  };
  CHECK(error("range <") ==
        "at column 8: expected a number, a 'text', true or false, found the end");
  CHECK(error("range < 1 and") == "at column 14: expected a field name, found the end");
  CHECK(error("(range < 1") == "at column 11: expected \")\", found the end");
  CHECK(error("range < 'open") == "at column 9: the text is not closed with '");
  CHECK(error("range # 1") == "at column 7: unexpected \"#\"");
  CHECK(error("range < 1 range") ==
        "at column 11: expected and, or or the end of the filter, found \"range\"");
  CHECK(error("range < 1x") == "at column 9: \"1x\" is not a number");
  CHECK(error("5 > range") == "at column 1: expected a field name, found \"5\""); // field first
}
