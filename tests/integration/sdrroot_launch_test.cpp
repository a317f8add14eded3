// `rsca launch SAD` against a real domain, as `rsca validate` reads the same SAD (issue 39, items
// 3 and 4): a SAD kept outside the SDR root its names resolve in launches as it validates, and an
// --assign of a component the SAD lacks is refused before anything is installed.
#include <filesystem>

#include <catch2/catch.hpp>

#include "domain_fixture.hpp"

using namespace rsca::test;
using rsca::control::Json;

namespace {

const fs::path kHealthyToCopy = kTestSdr / "dom/waveforms/Healthy/Healthy.sad.xml";

// What the domain has installed, and the folders of its repository (installs, staging leftovers).
std::pair<Json, std::vector<fs::path>> installed_and_folders(TestDomain &domain) {
  auto reply = domain.call("domain.installed");
  REQUIRE(reply.has_value());
  std::vector<fs::path> folders;
  const fs::path repository = domain.run_dir() / "repository";
  if (fs::exists(repository))
    for (const auto &entry : fs::recursive_directory_iterator(repository))
      folders.push_back(entry.path());
  return {reply->at("applications"), folders};
}

} // namespace

// `validate --sdrroot X SAD` said ok of a SAD kept outside X, and its launch refused it with its
// path cut to 54 bytes, labelled `rsca install`.
TEST_CASE("a SAD kept outside the SDR root it names launches as it validates",
          "[integration][domain][install][sdrroot]") {
  TestDomain domain(1);
  const fs::path folder =
      domain.run_dir() / "a-folder-named-at-length-so-that-the-path-runs-past-54-bytes";
  fs::create_directories(folder);
  const fs::path sad = folder / "Healthy.sad.xml";
  fs::copy_file(kHealthyToCopy, sad);
  REQUIRE(sad.string().size() > 54);

  auto [valid_rc, valid] = domain.cli({"validate", "--sdrroot", kTestSdr.string(), sad.string()});
  INFO(valid);
  CHECK(valid_rc == 0);
  auto [rc, out] = domain.cli({"launch", "--sdrroot", kTestSdr.string(), sad.string()});
  INFO(out);
  REQUIRE(rc == 0);
  CHECK_THAT(out, Catch::Contains("launched Healthy"));
  REQUIRE(domain.call("app.release", Json{{"app", "Healthy"}}).has_value());
  domain.require_clean({});
}

// An --assign of a component the SAD lacks went with the install, which replaced the installation
// of its name before the domain refused the assignment.
TEST_CASE("a launch that assigns a component its SAD lacks is refused before anything is "
          "installed",
          "[integration][domain][install][failure]") {
  TestDomain domain(1);
  domain.install("Healthy");
  const auto before = installed_and_folders(domain);

  auto [rc, out] = domain.cli({"launch", "--sdrroot", kTestSdr.string(), "--assign",
                               "Victim_2=node1:GPP_1", kHealthyToCopy.string()});
  INFO(out);
  CHECK(rc == 2); // usage
  CHECK_THAT(out, Catch::Contains("--assign Victim_2: Healthy has no component \"Victim_2\", did "
                                  "you mean \"Victim_1\"?"));
  CHECK_THAT(out, Catch::Contains("nothing was installed"));
  CHECK_THAT(out, !Catch::Contains("installed Healthy"));
  CHECK(installed_and_folders(domain) == before);
  domain.require_clean({});
}
