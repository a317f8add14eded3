// What a component's built code declares (profile/code_description.hpp) against its profiles,
// before a launch (issue 39, item 2): the SDK writes the description beside the executable at
// build time; `rsca validate` and `rsca launch` of a SAD find a property the code binds that the
// PRF lacks, as the component would have at its start.
#include <filesystem>
#include <fstream>

#include <catch2/catch.hpp>

#include "domain_fixture.hpp"
#include "profile/code_description.hpp"

using namespace rsca::test;
using rsca::control::Json;

namespace {

// An SDR root holding the Producer example as a user's component is installed (its code and the
// code's description beside its SPD), and an application of it alone.
struct ProducerSdr {
  fs::path root;
  fs::path sad;
  fs::path prf;

  explicit ProducerSdr(const fs::path &dir) : root(dir / "sdr") {
    const fs::path component = root / "dom/components/Producer";
    fs::create_directories(component);
    for (const char *file : {"Producer.spd.xml", "Producer.prf.xml", "Producer.scd.xml"})
      fs::copy_file(kSource / "profiles/dom/components/Producer" / file, component / file);
    // The code itself is never run here, only its description read: a stand-in of its name keeps
    // the install under its size bound in every build (a sanitizer build's executable is ~70 MB).
    std::ofstream(component / "rsca-producer") << "#!/bin/sh\nexit 0\n";
    fs::copy_file(kBin / "rsca-producer.rsca-code.json",
                  component / "rsca-producer.rsca-code.json");
    prf = component / "Producer.prf.xml";
    sad = root / "dom/waveforms/Solo/Solo.sad.xml";
    fs::create_directories(sad.parent_path());
    std::ofstream(sad) << R"(<?xml version="1.0" encoding="UTF-8"?>
<softwareassembly id="DCE:rsca-test-Solo" name="Solo">
  <componentfiles>
    <componentfile id="Producer_file" type="SPD">
      <localfile name="/components/Producer/Producer.spd.xml"/>
    </componentfile>
  </componentfiles>
  <partitioning>
    <componentplacement>
      <componentfileref refid="Producer_file"/>
      <componentinstantiation id="Producer_1">
        <usagename>Producer_1</usagename>
      </componentinstantiation>
    </componentplacement>
  </partitioning>
  <assemblycontroller>
    <componentinstantiationref refid="Producer_1"/>
  </assemblycontroller>
</softwareassembly>
)";
  }

  // The PRF with property `id` renamed: the code still binds `id`.
  void misspell_in_prf(const std::string &id) {
    std::ifstream in(prf);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string from = "id=\"" + id + "\"";
    const auto at = text.find(from);
    REQUIRE(at != std::string::npos);
    text.replace(at, from.size(), "id=\"" + id + "2\"");
    std::ofstream(prf, std::ios::trunc) << text;
  }
};

} // namespace

TEST_CASE("the SDK writes what a component's code declares beside its executable",
          "[integration][sdk][code]") {
  const auto description =
      rsca::profile::read_code_description(kBin / "rsca-producer.rsca-code.json");
  REQUIRE(description.has_value());
  std::vector<std::string> ports;
  for (const auto &p : description->ports)
    ports.push_back(p.name);
  CHECK_THAT(ports, Catch::VectorContains(std::string("samples_out")));
  CHECK_THAT(description->properties, Catch::VectorContains(std::string("rate_hz")));
}

TEST_CASE("validate and launch refuse an application whose component's code binds a property "
          "its PRF does not define",
          "[integration][domain][install][code]") {
  TestDomain domain(1);
  ProducerSdr sdr(domain.run_dir());
  {
    auto [rc, out] = domain.cli({"validate", "--sdrroot", sdr.root.string(), sdr.sad.string()});
    INFO(out);
    REQUIRE(rc == 0); // as built, the code fits its profiles
  }
  sdr.misspell_in_prf("rate_hz");
  const std::string misfit = "property \"rate_hz\" is bound, but the PRF does not define it";
  {
    auto [rc, out] = domain.cli({"validate", "--sdrroot", sdr.root.string(), sdr.sad.string()});
    INFO(out);
    CHECK(rc != 0);
    CHECK_THAT(out, Catch::Contains(misfit));
  }
  auto [rc, out] = domain.cli({"launch", "--sdrroot", sdr.root.string(), sdr.sad.string()});
  INFO(out);
  CHECK(rc == 1); // kInvalidProfile: refused before anything is installed
  CHECK_THAT(out, Catch::Contains(misfit));
  auto installed = domain.call("domain.installed");
  REQUIRE(installed.has_value());
  CHECK(installed->at("applications").empty());
  domain.require_clean({});
}
