// The XML reader module is loaded while profiles are read and unloaded afterwards, taking Xerces
// and its libraries out of the process.
#include <cstdlib>
#include <fstream>
#include <string>

#include <catch2/catch.hpp>

#include "profile/profile_loader.hpp"
#include "profile/xml_reader.hpp"

using namespace rsca;

namespace {

bool mapped(const std::string &library) {
  std::ifstream maps("/proc/self/maps");
  std::string line;
  while (std::getline(maps, line))
    if (line.find(library) != std::string::npos)
      return true;
  return false;
}

const std::filesystem::path kProducerSpd =
    std::filesystem::path(RSCA_SOURCE_DIR) / "profiles/dom/components/Producer/Producer.spd.xml";

} // namespace

TEST_CASE("Xerces is in the process only while a loader that read profiles lives",
          "[profile][xml]") {
  REQUIRE_FALSE(mapped("libxerces-c"));
  std::shared_ptr<const profile::ResolvedSoftPkg> softpkg;
  {
    profile::ProfileLoader loader;
    auto loaded = loader.load_softpkg(kProducerSpd);
    REQUIRE(loaded.has_value());
    softpkg = *loaded;
    CHECK(profile::XmlReader::loaded());
    CHECK(mapped("libxerces-c"));
  }
  CHECK_FALSE(profile::XmlReader::loaded());
  if (profile::XmlReader::kUnloads) {
    CHECK_FALSE(mapped("librsca_xml_reader"));
    CHECK_FALSE(mapped("libxerces-c"));
  }
  // The model outlives the reader that built it.
  CHECK(softpkg->spd->name == "Producer");
  REQUIRE(softpkg->properties != nullptr);
}

TEST_CASE("the XML reader loads again after it was unloaded", "[profile][xml]") {
  for (int round = 0; round < 2; ++round) {
    profile::ProfileLoader loader;
    auto loaded = loader.load_softpkg(kProducerSpd);
    REQUIRE(loaded.has_value());
    CHECK((*loaded)->spd->name == "Producer");
  }
  CHECK_FALSE(profile::XmlReader::loaded());
}

TEST_CASE("a missing XML reader module is a clear error, not a crash", "[profile][xml]") {
  REQUIRE_FALSE(profile::XmlReader::loaded());
  ::setenv("RSCA_XML_READER", "/nonexistent/librsca_xml_reader.so", 1);
  auto document = profile::read_xml_profile(kProducerSpd);
  ::unsetenv("RSCA_XML_READER");
  REQUIRE_FALSE(document.has_value());
  CHECK_THAT(document.error().to_string(),
             Catch::Contains("cannot load the XML reader module") &&
                 Catch::Contains("/nonexistent/librsca_xml_reader.so"));
  CHECK(profile::read_xml_profile(kProducerSpd).has_value()); // found where it is by default
}
