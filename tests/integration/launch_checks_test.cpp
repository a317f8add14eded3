// `rsca launch SAD` checks the user's files before it installs anything, and `rsca plan SAD` is a
// dry run (issue 39, item 5): a SAD a launch would refuse never replaces the installation of its
// name nor stays installed, its errors name the user's file, and a plan installs nothing.
#include <filesystem>

#include <catch2/catch.hpp>

#include "domain_fixture.hpp"

using namespace rsca::test;
using rsca::control::Json;

namespace {

// Healthy's SAD with its connection wired to a port its component lacks, under the name Healthy.
const fs::path kMiswired = kTestSdr / "dom/waveforms/HealthyMiswired/HealthyMiswired.sad.xml";
const fs::path kHealthy = kTestSdr / "dom/waveforms/Healthy/Healthy.sad.xml";

Json installed(TestDomain &domain) {
  auto reply = domain.call("domain.installed");
  REQUIRE(reply.has_value());
  return reply->at("applications");
}

// What the domain's repository holds besides its store: installed folders and staging leftovers.
std::vector<std::string> repository_folders(const TestDomain &domain) {
  std::vector<std::string> out;
  for (const char *where : {"applications", ".staging"}) {
    const fs::path dir = domain.run_dir() / "repository" / where;
    if (fs::exists(dir))
      for (const auto &entry : fs::directory_iterator(dir))
        out.push_back(entry.path().lexically_relative(domain.run_dir()).string());
  }
  return out;
}

// A launch of the miswired SAD from its file is refused naming the user's file, line and column.
void launch_miswired_is_refused(TestDomain &domain) {
  auto [rc, out] = domain.cli({"launch", "--sdrroot", kTestSdr.string(), kMiswired.string()});
  INFO(out);
  CHECK(rc == 1); // kInvalidProfile
  CHECK_THAT(out, Catch::Contains(kMiswired.string() + ":40:21"));
  CHECK_THAT(out, Catch::Contains("has no provides port \"no_such_port\""));
  CHECK_THAT(out, !Catch::Contains("repository"));
}

} // namespace

TEST_CASE("a SAD a launch would refuse, launched from its file, leaves the good installation of "
          "its name as it was",
          "[integration][domain][install][failure]") {
  TestDomain domain(1);
  domain.install("Healthy");
  const Json before = installed(domain);
  const auto folders_before = repository_folders(domain);

  launch_miswired_is_refused(domain);

  CHECK(installed(domain) == before);
  CHECK(repository_folders(domain) == folders_before);
  auto [rc, out] = domain.cli({"launch", "Healthy"});
  INFO(out);
  REQUIRE(rc == 0);
  REQUIRE(domain.call("app.release", Json{{"app", "Healthy"}}).has_value());
  domain.require_clean({});
}

TEST_CASE("a SAD a launch would refuse, not installed before, is not installed by its launch",
          "[integration][domain][install][failure]") {
  TestDomain domain(1);
  launch_miswired_is_refused(domain);
  CHECK(installed(domain).empty());
  CHECK(repository_folders(domain).empty());
  domain.require_clean({});
}

TEST_CASE("rsca plan of a SAD file reports its plan and installs nothing",
          "[integration][domain][install][plan]") {
  TestDomain domain(1);
  auto [rc, out] = domain.cli({"plan", "--sdrroot", kTestSdr.string(), kHealthy.string()});
  INFO(out);
  CHECK(rc == 0);
  CHECK_THAT(out, Catch::Contains("plan for Healthy"));
  CHECK_THAT(out, Catch::Contains("admitted"));
  CHECK_THAT(out, Catch::Contains("Producer_1"));
  CHECK_THAT(out, Catch::Contains("node1:GPP_1"));
  CHECK(installed(domain).empty());
  CHECK(repository_folders(domain).empty());
}

TEST_CASE("a failed launch of a SAD file uninstalls what it installed, and only that",
          "[integration][domain][install][failure]") {
  TestDomain domain(1);
  const fs::path sad = kTestSdr / "dom/waveforms/MissingExecutable/MissingExecutable.sad.xml";
  auto [rc, out] = domain.cli({"launch", "--sdrroot", kTestSdr.string(), sad.string()});
  INFO(out);
  CHECK(rc == 6); // failed, rolled back
  CHECK_THAT(out, Catch::Contains("failed at step 'execute'"));
  CHECK_THAT(out, Catch::Contains("MissingExecutable is uninstalled again"));
  // The file the error is about is the user's, not the domain's copy of it.
  CHECK_THAT(out, Catch::Contains((kTestSdr / "dom/components/Missing/Missing.spd.xml").string() +
                                  ": code file rsca-no-such-program"));
  CHECK_THAT(out, !Catch::Contains("repository"));
  CHECK(installed(domain).empty());
  CHECK(repository_folders(domain).empty());

  // Installed before the launch: it is the user's, and stays.
  domain.install("MissingExecutable");
  const Json before = installed(domain);
  auto [again_rc, again] = domain.cli({"launch", "--sdrroot", kTestSdr.string(), sad.string()});
  INFO(again);
  CHECK(again_rc == 6);
  CHECK_THAT(again, !Catch::Contains("uninstalled"));
  CHECK_THAT(again, Catch::Contains("the installation of MissingExecutable it replaced is back"));
  CHECK(installed(domain) == before);
  domain.require_clean({});
}

// The hole the launch checks leave: a SAD that passes them all but whose launch fails replaced
// the good installation of its name. The install a launch makes is on trial until it ends.
TEST_CASE("a SAD that passes the checks but fails to launch, launched from its file, leaves the "
          "good installation of its name as it was",
          "[integration][domain][install][failure]") {
  TestDomain domain(1);
  domain.install("Healthy");
  const Json before = installed(domain);
  const auto folders_before = repository_folders(domain);
  const fs::path sad = kTestSdr / "dom/waveforms/HealthyUnlaunchable/HealthyUnlaunchable.sad.xml";

  auto [rc, out] = domain.cli({"launch", "--sdrroot", kTestSdr.string(), sad.string()});
  INFO(out);
  CHECK(rc == 6); // failed, rolled back
  CHECK_THAT(out, Catch::Contains("failed at step 'execute'"));
  CHECK_THAT(out, Catch::Contains("the installation of Healthy it replaced is back"));
  CHECK(installed(domain) == before);
  CHECK(repository_folders(domain) == folders_before); // nothing held aside is left

  // The installation that is back is the good one: it launches.
  auto [good_rc, good] = domain.cli({"launch", "Healthy"});
  INFO(good);
  REQUIRE(good_rc == 0);
  REQUIRE(domain.call("app.release", Json{{"app", "Healthy"}}).has_value());

  // A launch from a file that succeeds keeps its install, and what it replaced goes.
  auto [file_rc, file_out] =
      domain.cli({"launch", "--sdrroot", kTestSdr.string(),
                  (kTestSdr / "dom/waveforms/Healthy/Healthy.sad.xml").string()});
  INFO(file_out);
  REQUIRE(file_rc == 0);
  CHECK(repository_folders(domain) == folders_before);
  REQUIRE(domain.call("app.release", Json{{"app", "Healthy"}}).has_value());
  domain.require_clean({});
}
