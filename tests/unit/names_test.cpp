// What may be a name (of an application, a component, a port, a device, a node): one component
// of a path or an address, never a path.
#include <string>

#include <catch2/catch.hpp>

#include "common/names.hpp"

using rsca::check_name;
using rsca::excerpt;

TEST_CASE("ordinary names are names", "[unit][names]") {
  for (const char *name : {"ProducerConsumer", "rh.FM_mono_demo", "a", "Producer_1", "DCE:1234",
                           "app with spaces", "x..y"}) {
    INFO(name);
    CHECK(check_name("application name", name).has_value());
  }
  CHECK(check_name("application name", std::string(rsca::kMaxNameLength, 'a')).has_value());
}

TEST_CASE("paths, dot names, control characters, empty and over-long names are not names",
          "[unit][names]") {
  const std::string nul_inside("a\0b", 3);
  const std::pair<std::string, const char *> refused[] = {
      {"", "is empty"},
      {".", "names a folder"},
      {"..", "names a folder"},
      {"../../victim", "starts with '.'"},
      {"a/../../victim", "path separator"},
      {"/etc", "path separator"},
      {"a\\b", "path separator"},
      {".staging-1", "starts with '.'"},
      {"bell\a", "control character"},
      {"line\nbreak", "control character"},
      {nul_inside, "control character"},
      {std::string(rsca::kMaxNameLength + 1, 'a'), "256 bytes long"},
  };
  for (const auto &[name, why] : refused) {
    INFO(excerpt(name));
    auto checked = check_name("application name", name);
    REQUIRE_FALSE(checked.has_value());
    CHECK_THAT(checked.error(), Catch::Contains(why));
    CHECK_THAT(checked.error(), Catch::StartsWith("application name"));
  }
}

TEST_CASE("an error quotes a bounded excerpt of a huge name", "[unit][names]") {
  const std::string huge(7 * 1024 * 1024, 'x');
  auto checked = check_name("application name", huge);
  REQUIRE_FALSE(checked.has_value());
  CHECK(checked.error().size() < 200);
  CHECK_THAT(checked.error(), Catch::Contains("7340032 bytes"));
  CHECK(excerpt("short") == "short");
  CHECK(excerpt("tab\there", 64) == "tab?here");
}
