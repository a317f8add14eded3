// A component's code description (profile/code_description.hpp): read back as written, refused
// when it is not one, and compared with the profiles as the component's own start compares them.
#include <fstream>

#include <catch2/catch.hpp>

#include "profile/code_description.hpp"
#include "temp_dir.hpp"

using namespace rsca::profile;

TEST_CASE("a code description reads back as it was written", "[code_description]") {
  rsca::test::TempDir dir;
  const CodeDescription written{{{"out", PortDirection::Uses, false},
                                 {"in", PortDirection::Provides, false},
                                 {"peer", PortDirection::Uses, true}},
                                {"rate_hz", "stream"}};
  const auto file = dir.path() / "code.rsca-code.json";
  std::ofstream(file) << to_json_text(written);
  auto read = read_code_description(file);
  REQUIRE(read.has_value());
  REQUIRE(read->ports.size() == 3);
  CHECK(read->ports[1].name == "in");
  CHECK(read->ports[1].direction == PortDirection::Provides);
  CHECK(read->ports[2].resource);
  CHECK(read->properties == written.properties);
}

TEST_CASE("a file that is no code description of this version is refused, naming it",
          "[code_description]") {
  rsca::test::TempDir dir;
  const auto file = dir.path() / "bad.rsca-code.json";
  for (const char *text : {"[]", R"({"version": 99, "ports": [], "properties": []})",
                           R"({"version": 1, "ports": [{"name": "a", "direction": "sideways"}],
                              "properties": []})",
                           R"({"version": 1, "ports": [], "properties": [7]})", "not json"}) {
    std::ofstream(file, std::ios::trunc) << text;
    auto read = read_code_description(file);
    INFO(text);
    REQUIRE_FALSE(read.has_value());
    CHECK(read.error().diagnostics().front().where.file == file.string());
  }
}

TEST_CASE("a code's port its SCD lacks and a property its PRF lacks are misfits",
          "[code_description]") {
  SoftwareComponent scd;
  scd.ports.push_back({});
  scd.ports.back().name = "out";
  scd.ports.back().direction = PortDirection::Uses;
  const CodeDescription code{
      {{"out", PortDirection::Uses, false}, {"output", PortDirection::Uses, false}},
      {"length", "lenght2"}};
  SimpleProperty length;
  length.id = "length";
  const auto misfits = code_misfits(code, &scd, {PropertyDefinition{length}});
  REQUIRE(misfits.size() == 2);
  CHECK(misfits[0] == "the component has uses port \"output\", which its SCD does not declare");
  CHECK(misfits[1] == "property \"lenght2\" is bound, but the PRF does not define it");
}
