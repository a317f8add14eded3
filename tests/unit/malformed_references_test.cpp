// Malformed profiles, continued from malformed_test.cpp: problems between elements and files
// (dangling references, duplicate ids, missing files, dependency cycles, a descriptor of the
// wrong type, a file outside its SDR root), each failing with the rule it breaks at the file, line
// and column a user needs to fix it. Fixtures: tests/data/malformed/.
#include "profile/descriptor.hpp"
#include "profile/profile_loader.hpp"
#include "profile/xml_document.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "malformed_fixture.hpp"

namespace fs = std::filesystem;
using namespace rsca;
using namespace rsca::profile;
using namespace rsca::test;
using Catch::Contains;

// ---------------------------------------------------------------------------------------------
// Dangling references.

TEST_CASE("a componentfileref naming no componentfile", "[malformed][dangling]") {
  single_file_error(
      fixture("dangling/componentfileref.sad.xml"), "dangling-ref", 11, 46,
      {"componentfileref refid \"missing_spd\" names no componentfile", "(known: comp_spd)"});
}

TEST_CASE("a connection naming no componentinstantiation", "[malformed][dangling]") {
  const fs::path file = fixture("dangling/connection_ref.sad.xml");
  auto result = read_descriptor(file);
  const Error &error = error_of(result);
  REQUIRE(error.diagnostics().size() == 1);
  const Diagnostic &d = error.diagnostics().front();
  INFO("diagnostic: " << to_string(d));
  CHECK(d.rule == "dangling-ref");
  CHECK(d.where.file == file.string());
  CHECK(d.where.line == 26); // the <componentinstantiationref refid="ghost_1"/> itself
  CHECK_THAT(d.message,
             Contains("connection \"link\" refers to componentinstantiation \"ghost_1\""));
  CHECK_THAT(d.message, Contains("which this file does not define"));
}

TEST_CASE("an assemblycontroller naming no componentinstantiation", "[malformed][dangling]") {
  single_file_error(fixture("dangling/assemblycontroller.sad.xml"), "dangling-ref", 16, 49,
                    {"assemblycontroller names componentinstantiation \"ghost_1\"",
                     "which this SAD does not define"});
}

TEST_CASE("an SPD implref naming an implementation the dependency lacks", "[malformed][dangling]") {
  const fs::path root = fixture("dangling/implref");
  const fs::path spd = root / "dom/components/comp/comp.spd.xml";
  ProfileLoader loader(root);
  auto result = loader.load_softpkg(spd);
  const Diagnostic &d = find_rule(error_of(result), "dangling-ref");
  INFO("diagnostic: " << to_string(d));
  CHECK(d.where.file == loader_name(spd));
  CHECK(d.where.line == 14); // the <implref refid="fpga"/> itself
  CHECK_THAT(d.message, Contains("implref \"fpga\" names no implementation of lib"));
  CHECK_THAT(d.message, Contains("(it has: cpp)"));
}

TEST_CASE("a SAD override of a property the PRF does not define is ignored with a warning",
          "[malformed][dangling][redhawk]") {
  // REDHAWK warns and ignores such an override; so does rsca (--strict refuses it).
  const fs::path root = fixture("dangling/unknown_property");
  const fs::path sad = root / "dom/waveforms/app/app.sad.xml";
  ProfileLoader loader(root);
  auto result = loader.load_application(sad);
  REQUIRE(result.has_value());
  CHECK(result->warnings.empty()); // nothing that stops a launch
  REQUIRE(result->tolerated.size() == 1);
  check(result->tolerated.front(), "unknown-property", loader_name(sad), 14, 46,
        {"componentinstantiation \"comp_1\"", "property \"gain\" is not defined by comp.prf.xml",
         "the override is ignored"},
        Severity::Warning);
}

// ---------------------------------------------------------------------------------------------
// Duplicate ids.

TEST_CASE("two componentinstantiations with one id", "[malformed][duplicate]") {
  single_file_error(fixture("duplicate/instantiation_id.sad.xml"), "duplicate-id", 16, 44,
                    {"componentinstantiation id \"comp_1\" is defined more than once"});
}

TEST_CASE("two PRF properties with one id", "[malformed][duplicate]") {
  single_file_error(fixture("duplicate/property_id.prf.xml"), "duplicate-id", 8, 53,
                    {"property id \"gain\" is defined more than once"});
}

// ---------------------------------------------------------------------------------------------
// Missing files, cycles, wrong descriptor types: problems between files.

// A missing file is an error only where it is needed (REDHAWK reads such a package): the loader
// reads the package without it, marks it unavailable with where the file is named, and warns.

TEST_CASE("a SAD naming an SPD that does not exist", "[malformed][missing-file][redhawk]") {
  const fs::path root = fixture("missing_file/spd");
  const fs::path sad = root / "dom/waveforms/app/app.sad.xml";
  ProfileLoader loader(root);
  auto result = loader.load_application(sad);
  REQUIRE(result.has_value());
  REQUIRE(result->component_files.size() == 1);
  const auto &pkg = *result->component_files.begin()->second;
  CHECK(pkg.spd->implementations.empty());
  REQUIRE(pkg.unavailable.size() == 1);
  check(pkg.unavailable.front(), "missing-file", loader_name(sad), 6, 56,
        {"the file named here does not exist",
         loader_name(root / "dom/components/comp/comp.spd.xml")});
  REQUIRE(result->tolerated.size() == 1);
  check(result->tolerated.front(), "missing-file", loader_name(sad), 6, 56, {"cannot run"},
        Severity::Warning);
}

TEST_CASE("an SPD naming a PRF that does not exist", "[malformed][missing-file][redhawk]") {
  const fs::path root = fixture("missing_file/prf");
  const fs::path spd = root / "dom/components/comp/comp.spd.xml";
  const std::string prf = loader_name(root / "dom/components/comp/comp.prf.xml");

  SECTION("the package on its own") {
    ProfileLoader loader(root);
    auto result = loader.load_softpkg(spd);
    REQUIRE(result.has_value());
    CHECK((*result)->properties == nullptr);
    REQUIRE((*result)->unavailable.size() == 1);
    check((*result)->unavailable.front(), "missing-file", loader_name(spd), 8, 37,
          {"the file named here does not exist", prf});
    REQUIRE((*result)->warnings.size() == 1);
    CHECK((*result)->warnings.front().severity == Severity::Warning);
  }
  SECTION("through an application: read, with the SPD's warning") {
    const fs::path sad = root / "dom/waveforms/app/app.sad.xml";
    ProfileLoader loader(root);
    auto result = loader.load_application(sad);
    REQUIRE(result.has_value());
    REQUIRE(result->tolerated.size() == 1);
    check(result->tolerated.front(), "missing-file", loader_name(spd), 8, 37, {prf},
          Severity::Warning);
  }
  SECTION("validate reports it as a warning") {
    ProfileLoader loader(root);
    auto result = loader.validate(spd);
    REQUIRE(result.has_value());
    REQUIRE(result->warnings.size() == 1);
    CHECK(result->warnings.front().rule == "missing-file");
  }
}

TEST_CASE("softpkg dependencies forming a cycle", "[malformed][dependency-cycle]") {
  const fs::path root = fixture("cycle");
  const fs::path a = root / "dom/deps/a/a.spd.xml";
  const fs::path b = root / "dom/deps/b/b.spd.xml";

  SECTION("starting from a") {
    ProfileLoader loader(root);
    auto result = loader.load_softpkg(a);
    const Error &error = error_of(result);
    check(find_rule(error, "dependency-cycle"), "dependency-cycle", loader_name(b), 13, 46,
          {"a.spd.xml -> b.spd.xml -> a.spd.xml"});
    check(find_rule(error, "invalid-ref"), "invalid-ref", loader_name(a), 13, 46, {loader_name(b)});
  }
  SECTION("starting from b") {
    ProfileLoader loader(root);
    auto result = loader.load_softpkg(b);
    check(find_rule(error_of(result), "dependency-cycle"), "dependency-cycle", loader_name(a), 13,
          46, {"b.spd.xml -> a.spd.xml -> b.spd.xml"});
  }
}

TEST_CASE("a SAD componentfile naming a PRF instead of an SPD", "[malformed][wrong-descriptor]") {
  const fs::path root = fixture("wrong_descriptor");
  const fs::path sad = root / "dom/waveforms/app/app.sad.xml";
  ProfileLoader loader(root);
  auto result = loader.load_application(sad);
  const Error &error = error_of(result);
  REQUIRE(error.diagnostics().size() == 1);
  check(error.diagnostics().front(), "wrong-descriptor", loader_name(sad), 6, 56,
        {"SPD", loader_name(root / "dom/components/comp/comp.prf.xml") + " is a PRF"});
}

TEST_CASE("an application outside any SDR root", "[malformed][sdrroot]") {
  // Generated, since the source tree itself might lie below a folder named dom or dev.
  TempDir dir;
  const fs::path sad = dir.path() / "app.sad.xml";
  write_file(sad, padded_sad(0));
  ProfileLoader loader;
  auto result = loader.load_application(sad);
  const Error &error = error_of(result);
  REQUIRE(error.diagnostics().size() == 1);
  check(error.diagnostics().front(), "sdrroot", sad.string(), 0, 0,
        {"no SDR root found", "--sdrroot"});
}

TEST_CASE("a file name leaving the SDR root is refused", "[malformed][outside-sdrroot]") {
  TempDir dir;
  const fs::path sad = dir.path() / "sdr/dom/waveforms/app/app.sad.xml";
  fs::create_directories(sad.parent_path());
  write_file(sad, R"(<?xml version="1.0" encoding="UTF-8"?>
<softwareassembly id="DCE:escape" name="escape">
  <componentfiles>
    <componentfile id="f" type="SPD">
      <localfile name="/../../../../../../../../etc/hostname"/>
    </componentfile>
  </componentfiles>
  <partitioning>
    <componentplacement>
      <componentfileref refid="f"/>
      <componentinstantiation id="c"/>
    </componentplacement>
  </partitioning>
  <assemblycontroller><componentinstantiationref refid="c"/></assemblycontroller>
</softwareassembly>
)");
  ProfileLoader loader;
  auto app = loader.load_application(sad);
  const Diagnostic &d = find_rule(error_of(app), "outside-sdrroot");
  CHECK(d.where.line == 5);
  CHECK_THAT(d.message, Contains("lies outside the SDR root"));
}
