// Strict for profiles written for rsca, lenient for REDHAWK's (issue 39, item 4), and where a
// profile's SDR root is found (item 3): the mark of a REDHAWK profile (its SCA DOCTYPE), what a
// launch refuses of each (profile::launch_refusals), the "did you mean" of a misspelled name, and
// SdrRoot::locate's order.
#include <filesystem>
#include <fstream>
#include <string>

#include <catch2/catch.hpp>

#include "common/names.hpp"
#include "profile/application_checks.hpp"
#include "profile/profile_loader.hpp"
#include "temp_dir.hpp"

using namespace rsca;
using namespace rsca::profile;
namespace fs = std::filesystem;

namespace {

const fs::path kStrictSdr = fs::path(RSCA_TEST_DATA_DIR) / "integration";

fs::path strict_test_sad(const std::string &name) {
  return kStrictSdr / "dom/waveforms" / name / (name + ".sad.xml");
}

void write_strict_test_file(const fs::path &file, const std::string &text) {
  fs::create_directories(file.parent_path());
  std::ofstream(file) << text;
}

} // namespace

TEST_CASE("a profile with the SCA DOCTYPE is marked as written for REDHAWK, one without as rsca's",
          "[profile][strict]") {
  const std::string body = "<properties>\n</properties>\n";
  auto redhawk = read_xml_profile_text(
      "<?xml version=\"1.0\"?>\n<!DOCTYPE properties PUBLIC \"-//JTRS//DTD SCA V2.2.2 PRF//EN\" "
      "\"properties.dtd\">\n" +
          body,
      "redhawk.prf.xml");
  REQUIRE(redhawk.has_value());
  CHECK(redhawk->redhawk);
  auto own = read_xml_profile_text("<?xml version=\"1.0\"?>\n" + body, "rsca.prf.xml");
  REQUIRE(own.has_value());
  CHECK_FALSE(own->redhawk);

  ProfileLoader loader(kStrictSdr);
  auto strict = loader.load_application(strict_test_sad("StrictMisspelled"));
  REQUIRE(strict.has_value());
  CHECK_FALSE(strict->sad->redhawk);
  CHECK(is_strict(*strict));
  auto lenient = loader.load_application(strict_test_sad("RedhawkMisspelled"));
  REQUIRE(lenient.has_value());
  CHECK(lenient->sad->redhawk);
  CHECK_FALSE(is_strict(*lenient));
}

TEST_CASE("a launch refuses a misspelled override of an rsca profile and ignores a REDHAWK one's",
          "[profile][strict]") {
  ProfileLoader loader(kStrictSdr);
  auto strict = loader.load_application(strict_test_sad("StrictMisspelled"));
  REQUIRE(strict.has_value());
  const auto refused = launch_refusals(*strict);
  REQUIRE(refused.size() == 1);
  CHECK(refused.front().rule == "unknown-property");
  CHECK(refused.front().severity == Severity::Error);
  CHECK(refused.front().where.line == 19);
  CHECK_THAT(refused.front().message, Catch::Contains("property \"rate_hzz\" is not defined by "
                                                      "Producer.prf.xml (did you mean "
                                                      "\"rate_hz\"?)"));

  auto lenient = loader.load_application(strict_test_sad("RedhawkMisspelled"));
  REQUIRE(lenient.has_value());
  CHECK(launch_refusals(*lenient).empty());
  REQUIRE(lenient->tolerated.size() == 1);
  CHECK(lenient->tolerated.front().severity == Severity::Warning);
  CHECK_THAT(lenient->tolerated.front().message, Catch::Contains("the override is ignored"));
}

TEST_CASE("the closest name is offered for a misspelling, and none for another name",
          "[names][strict]") {
  const std::vector<std::string> ids{"rate_hz", "payload_size", "message"};
  CHECK(closest_name("rate_hzz", ids) == "rate_hz");
  CHECK(closest_name("Rate_Hz", ids) == "rate_hz");
  CHECK(closest_name("Victim_2", {"Producer_1", "Victim_1"}) == "Victim_1");
  CHECK(closest_name("frequency", ids).empty());
  CHECK(closest_name("x", {}).empty());
}

TEST_CASE("an SDR root is found from --sdrroot, the folders above, the project, then SDRROOT",
          "[profile][sdrroot]") {
  rsca::test::TempDir dir;
  const fs::path given = dir.path() / "given";
  const fs::path fallback = dir.path() / "env";
  const fs::path in_root = dir.path() / "sdr/dom/waveforms/A/A.sad.xml";
  const fs::path in_project = dir.path() / "Foo/Foo.sad.xml";
  const fs::path loose = dir.path() / "loose/B.sad.xml";
  write_strict_test_file(in_root, "");
  write_strict_test_file(in_project, "");
  write_strict_test_file(dir.path() / "Foo/CMakeLists.txt", "");
  write_strict_test_file(loose, "");

  CHECK(SdrRoot::locate(in_root, given, fallback)->path() == given);
  CHECK(SdrRoot::locate(in_root, std::nullopt, fallback)->path() == dir.path() / "sdr");
  auto project = SdrRoot::locate(in_project, std::nullopt, fallback);
  REQUIRE(project.has_value());
  CHECK(project->is_project());
  CHECK(project->path() == dir.path() / "Foo");
  // Its install lays the project's side-by-side files out; in place, a name is its file's.
  CHECK(project->resolve("/components/Foo/Foo.spd.xml", in_project, SdrTree::Dom) ==
        dir.path() / "Foo/Foo.spd.xml");
  CHECK(SdrRoot::locate(loose, std::nullopt, fallback)->path() == fallback);
  CHECK_FALSE(SdrRoot::locate(loose, std::nullopt, std::nullopt).has_value());
}
