// REDHAWK 2.2's forms in a real domain (issue 23): an instance's affinity and loggingconfig
// reach its process through the node; a package that misses a file it names is installed (as
// REDHAWK reads it), and a launch of it fails at its first step naming the file, leaving nothing
// behind.
#include <algorithm>
#include <fstream>
#include <sstream>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "domain_fixture.hpp"

using namespace rsca::test;
using namespace std::chrono_literals;
using rsca::control::Json;

namespace {

std::string read_proc(long pid, const std::string &what) {
  std::ifstream in(fmt::format("/proc/{}/{}", pid, what));
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The value of one "Name:\tvalue" line of /proc/<pid>/status.
std::string status_field(long pid, const std::string &name) {
  std::istringstream lines(read_proc(pid, "status"));
  for (std::string line; std::getline(lines, line);)
    if (line.rfind(name + ":", 0) == 0)
      return line.substr(line.find_first_not_of(" \t", name.size() + 1));
  return {};
}

} // namespace

TEST_CASE("an instance's affinity and loggingconfig reach its process",
          "[integration][redhawk22]") {
  TestDomain domain;
  const Json app = domain.create("Pinned");
  const auto pids = pids_of(app);
  REQUIRE(pids.size() == 1);
  // affinity cpu 0: the node pinned the process (and its threads) to CPU 0.
  CHECK(status_field(pids.front(), "Cpus_allowed_list") == "0");
  // loggingconfig level DEBUG: REDHAWK's DEBUG_LEVEL 4 on its command line.
  std::string cmdline = read_proc(pids.front(), "cmdline");
  std::replace(cmdline.begin(), cmdline.end(), '\0', ' ');
  CHECK_THAT(cmdline, Catch::Contains("DEBUG_LEVEL 4"));
}

// A SAD whose component misses a file (its PRF, or its SPD altogether) installs with a warning,
// as REDHAWK reads it; a launch fails at its first step naming the component and the file.
static void check_missing(const std::string &application, const std::string &component,
                          const std::string &file) {
  TestDomain domain;
  auto [rc_install, installed] =
      domain.cli({"install", "--sdrroot", kTestSdr.string(),
                  (kTestSdr / fmt::format("dom/waveforms/{0}/{0}.sad.xml", application)).string()});
  INFO(installed);
  REQUIRE(rc_install == 0);
  CHECK_THAT(installed, Catch::Contains("warning: missing-file"));
  CHECK_THAT(installed, Catch::Contains(file));

  auto [rc, out] = domain.cli({"launch", application});
  INFO(out);
  CHECK(rc == 1); // the profile cannot be launched as it is (kInvalidProfile)
  CHECK_THAT(out, Catch::Contains("failed at step 'check'"));
  CHECK_THAT(out, Catch::Contains(fmt::format("component {} cannot be launched", component)));
  CHECK_THAT(out, Catch::Contains(file));
  domain.require_clean({});
  CHECK(domain.running_pids().empty());
}

TEST_CASE("a package missing its PRF installs with a warning and its launch fails naming the file",
          "[integration][redhawk22][failure]") {
  check_missing("MissingPrf", "NoPrf_1", "NoPrf.prf.xml");
}

TEST_CASE("a SAD naming an SPD that is not there installs with a warning and its launch fails "
          "naming the file",
          "[integration][redhawk22][failure]") {
  check_missing("MissingSpd", "Gone_1", "Gone.spd.xml");
}
