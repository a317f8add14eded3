// Unit tests of the name rule and of excerpts of untrusted text (common/names.hpp).
#include "common/names.hpp"

#include <string>

#include <catch2/catch.hpp>

using namespace rsca;

namespace {

std::string refusal(std::string_view what, std::string_view name) {
  auto checked = check_name(what, name);
  REQUIRE_FALSE(checked.has_value());
  const auto &d = checked.error().diagnostics().at(0);
  CHECK(d.rule == "name");
  return d.message;
}

} // namespace

TEST_CASE("names: what the domain's names look like is a name", "[names]") {
  for (const char *name : {"Producer_1", "node1", "DCE:9b4b1e8b-5d2a", "samples.out", "café", "a"})
    CHECK(check_name("the component", name).has_value());
  CHECK(check_name("the port", std::string(kMaxNameLength, 'p')).has_value());
}

TEST_CASE("names: empty, separators, control characters and long names are refused", "[names]") {
  CHECK(refusal("the port", "") == "the port has no name");
  CHECK(refusal("the component", "b/c") == "the component \"b/c\" is not a name: it holds a '/'");
  CHECK(refusal("the application", "a\nb") ==
        "the application \"a\\x0ab\" is not a name: it holds a control character");
  CHECK(refusal("the device", std::string("x\x7f", 2)) ==
        "the device \"x\\x7f\" is not a name: it holds a control character");
  CHECK(refusal("the port", std::string(kMaxNameLength + 1, 'p')) ==
        "the port \"pppppppppppppppppppppppppppppppppppppppp... (256 bytes)\" is too long a "
        "name: at most 255 bytes");
  const std::string message = refusal("the node", std::string(100 * 1024, '/'));
  CHECK(message.size() < 200);
}

TEST_CASE("names: an excerpt is bounded, escapes control characters and keeps UTF-8 whole",
          "[names]") {
  CHECK(excerpt("short") == "short");
  CHECK(excerpt(std::string(40, 'x')) == std::string(40, 'x'));
  CHECK(excerpt(std::string(41, 'x')) == std::string(40, 'x') + "... (41 bytes)");
  CHECK(excerpt("tab\there") == "tab\\x09here");
  // "é" is two bytes; a cut after the first would leave half of it.
  CHECK(excerpt("aé", 2) == "a... (3 bytes)");
  CHECK(excerpt(std::string(1 << 20, 'y')).size() < 80);
}

TEST_CASE("names: a name is never a path, nor one of the domain's own dot files", "[names]") {
  CHECK(refusal("the application", ".") ==
        "the application \".\" is not a name: it names a folder");
  CHECK(refusal("the application", "..") ==
        "the application \"..\" is not a name: it names a folder");
  CHECK(refusal("the application", "../../victim") ==
        "the application \"../../victim\" is not a name: it starts with '.'");
  CHECK(refusal("the application", ".staging") ==
        "the application \".staging\" is not a name: it starts with '.'");
  CHECK(refusal("the application", "a\\b") ==
        "the application \"a\\b\" is not a name: it holds a '\\'");
  CHECK(refusal("the application", "a/../../victim") ==
        "the application \"a/../../victim\" is not a name: it holds a '/'");
  CHECK(refusal("the application", std::string("a\0b", 3)) ==
        "the application \"a\\x00b\" is not a name: it holds a control character");
  // Dots inside a name are fine (REDHAWK's namespaced names).
  CHECK(check_name("the application", "rh.FM_mono_demo").has_value());
  CHECK(check_name("the application", "x..y").has_value());
}

TEST_CASE("names: a refusal of a 7 MB name quotes an excerpt", "[names]") {
  const std::string message = refusal("the application", std::string(7 * 1024 * 1024, 'x'));
  CHECK(message.size() < 200);
  CHECK_THAT(message, Catch::Contains("7340032 bytes"));
}
