// REDHAWK 2.2's forms that rsca reads (tests/data/redhawk22/): each is read, with the warning it
// deserves at the place it stands, and what it means is in the model. Refusing them is what
// `rsca validate --strict` does (tests/cli).
#include "profile/descriptor.hpp"
#include "profile/profile_loader.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include "malformed_fixture.hpp"

namespace fs = std::filesystem;
using namespace rsca;
using namespace rsca::profile;
using namespace rsca::test;
using Catch::Contains;

namespace {

const fs::path kRoot = fs::path(RSCA_SOURCE_DIR) / "tests/data/redhawk22";

std::string read_text(const fs::path &file) {
  std::ifstream in(file);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string file_of(std::string_view relative) {
  return loader_name(kRoot / relative);
}

// The one warning of `rule` at `line` among `warnings`; fails the test when there is not one.
const Diagnostic &warning_at(const std::vector<Diagnostic> &warnings, std::string_view rule,
                             int line) {
  const auto is_it = [&](const Diagnostic &d) { return d.rule == rule && d.where.line == line; };
  INFO("rule " << rule << " at line " << line);
  REQUIRE(std::count_if(warnings.begin(), warnings.end(), is_it) == 1);
  const Diagnostic &d = *std::find_if(warnings.begin(), warnings.end(), is_it);
  CHECK(d.severity == Severity::Warning);
  return d;
}

ResolvedApplication load_app(ProfileLoader &loader, std::string_view name) {
  auto app = loader.load_application(kRoot / "dom/waveforms" / name);
  INFO((app ? std::string() : app.error().to_string()));
  REQUIRE(app.has_value());
  return std::move(*app);
}

} // namespace

TEST_CASE("REDHAWK 2.2 PRF forms are read", "[redhawk22][prf]") {
  const auto file = kRoot / "dom/components/comp/comp.prf.xml";
  auto read = read_descriptor(file);
  INFO((read ? std::string() : read.error().to_string()));
  REQUIRE(read.has_value());
  const auto &prf = std::get<Properties>(*read);

  SECTION("an unknown kindtype is ignored with a warning") {
    const auto &d = warning_at(prf.warnings, "unknown-value", 6);
    CHECK(d.where.column == 37);
    CHECK_THAT(d.message, Contains("kindtype \"configuration\""));
    CHECK(common_of(*prf.find("gain")).kinds.empty()); // SCA's default (configure) applies
  }
  SECTION("complex boolean, a one-digit utctime, xsi:nil, an anonymous struct, a test") {
    CHECK(prf.warnings.size() == 1); // none of these deserve one
    const auto &flags = std::get<SimpleProperty>(*prf.find("flags"));
    REQUIRE(flags.value.has_value());
    CHECK(std::get<std::complex<double>>(*flags.value) == std::complex<double>(0, 1));
    const auto &when = std::get<SimpleProperty>(*prf.find("when"));
    CHECK(format_scalar(*when.value) == "2017:02:01::12:01:00.123000");
    const auto &names = std::get<SimpleSequenceProperty>(*prf.find("names"));
    REQUIRE(names.values.has_value());
    CHECK(names.values->size() == 2);
    const auto &points = std::get<StructSequenceProperty>(*prf.find("points"));
    CHECK(points.element.id.empty());
    CHECK(points.element.members.size() == 1);
  }
}

TEST_CASE("REDHAWK 2.2 SAD forms are read and modelled", "[redhawk22][sad]") {
  ProfileLoader loader(kRoot);
  const ResolvedApplication app = load_app(loader, "app.sad.xml");
  const std::string sad = file_of("dom/waveforms/app.sad.xml");
  const auto &w = app.tolerated;

  SECTION("hostcollocation usesdeviceref and reservation") {
    REQUIRE(app.sad->host_collocations.size() == 1);
    const auto &hc = app.sad->host_collocations.front();
    CHECK(hc.uses_device_refs == std::vector<std::string>{"radio"});
    REQUIRE(hc.cpu_cores.has_value());
    CHECK(*hc.cpu_cores == 1.5);
    CHECK_THAT(warning_at(w, "unknown-value", 31).message, Contains("reservation kind \"memory\""));
  }
  SECTION("affinity and loggingconfig of an instance") {
    const auto *ci = app.sad->find_instantiation("comp_1");
    REQUIRE(ci != nullptr);
    REQUIRE(ci->affinity.has_value());
    CHECK(ci->affinity->directive == ProcessorAffinity::Class::Cpu);
    CHECK(ci->affinity->value == "0");
    REQUIRE(ci->logging.has_value());
    CHECK(ci->logging->debug_level == 4); // DEBUG
    CHECK(ci->logging->uri == "file:///etc/comp.log4j");
    // A cgroup is REDHAWK's; rsca reads it and applies nothing.
    CHECK_FALSE(app.sad->find_instantiation("comp_2")->affinity.has_value());
    CHECK_THAT(warning_at(w, "unknown-value", 37).message, Contains("affinity class \"cgroup\""));
  }
  SECTION("a startorder that is no number, a componentfile type that is not SPD") {
    CHECK_FALSE(app.sad->find_instantiation("comp_1")->start_order.has_value());
    CHECK(warning_at(w, "value", 13).where.file == sad);
    CHECK_THAT(warning_at(w, "unknown-value", 5).message, Contains("type \"spd\""));
  }
  SECTION("two usesdevicedependencies, and a connection to the application's device") {
    REQUIRE(app.sad->uses_device_dependencies.size() == 2);
    CHECK(app.sad->uses_device_dependencies[1].id == "gps");
    const auto &to_radio = app.sad->connections.front();
    CHECK(to_radio.provides.target.kind == EndpointTarget::Kind::DeviceUsedByApplication);
    CHECK(to_radio.provides.target.usesrefid == "radio");
  }
  SECTION("overrides REDHAWK ignores: an empty number, a property the PRF lacks") {
    CHECK_THAT(warning_at(w, "empty-value", 16).message, Contains("property \"gain\""));
    CHECK_THAT(warning_at(w, "unknown-property", 17).message, Contains("\"volume\""));
    CHECK_THAT(warning_at(w, "unknown-property", 18).message,
               Contains("struct \"limits\" has no member \"limits::high\""));
    CHECK(app.warnings.empty()); // nothing here stops a launch by itself
  }
  SECTION("a domainfinder type nobody defines") {
    CHECK_THAT(warning_at(w, "unknown-value", 63).message, Contains("\"service\""));
  }
}

TEST_CASE("a usesdeviceref or deviceusedbyapplication naming no usesdevice is refused",
          "[redhawk22][sad][malformed]") {
  TempDir dir;
  const fs::path copy = dir.path() / "dom/waveforms/app.sad.xml";
  fs::create_directories(copy.parent_path());
  std::string text = read_text(kRoot / "dom/waveforms/app.sad.xml");
  const std::string from = "<usesdeviceref refid=\"radio\"/>";
  text.replace(text.find(from), from.size(), "<usesdeviceref refid=\"radar\"/>");
  write_file(copy, text);
  auto read = read_descriptor(copy);
  const Error &error = error_of(read);
  REQUIRE(error.diagnostics().size() == 1);
  check(error.diagnostics().front(), "dangling-ref", copy.string(), 29, 37,
        {"hostcollocation \"near_radio\" names usesdevice \"radar\""});
}

TEST_CASE("REDHAWK 2.2 DCD forms are read and modelled", "[redhawk22][dcd]") {
  ProfileLoader loader(kRoot);
  auto node = loader.load_node(kRoot / "dev/nodes/node.dcd.xml");
  INFO((node ? std::string() : node.error().to_string()));
  REQUIRE(node.has_value());
  const auto &ci = node->dcd->placements.front().instantiations.front();
  CHECK(ci.start_order == 0u);
  REQUIRE(ci.logging.has_value());
  CHECK(ci.logging->debug_level == 5); // TRACE
  REQUIRE(ci.device_requires.size() == 1);
  // White space inside elements that hold only attributes is no finding at all; the connection
  // to the DeviceManager and the bad value are. The DeviceManager SPD the DCD names
  // (/mgr/DeviceManager.spd.xml) is not in this root: it is found in rsca's own profiles, since
  // rsca-noded is the DeviceManager.
  // A device's value that does not fit its property: REDHAWK's DeviceManager logs it and starts
  // the device with its default; so do rsca's node and loader.
  CHECK(node->tolerated.size() == 2);
  CHECK_THAT(warning_at(node->tolerated, "value", 21).message, Contains("the override is ignored"));
  CHECK(std::none_of(node->tolerated.begin(), node->tolerated.end(),
                     [](const Diagnostic &d) { return d.rule == "missing-file"; }));
  CHECK_THAT(warning_at(node->tolerated, "dangling-ref", 38).message, Contains("DeviceManager"));
  CHECK(node->warnings.empty());
}

TEST_CASE("a DeviceManager SPD found nowhere is a warning, not an error", "[redhawk22][dcd]") {
  // The same node, its manager SPD renamed to one neither this root nor rsca's profiles hold.
  TempDir root("rsca-dcd-manager-");
  fs::copy(kRoot / "dev", root.path() / "dev", fs::copy_options::recursive);
  const fs::path dcd = root.path() / "dev/nodes/node.dcd.xml";
  std::string text = read_text(dcd);
  const std::string named = "/mgr/DeviceManager.spd.xml";
  REQUIRE(text.find(named) != std::string::npos);
  text.replace(text.find(named), named.size(), "/mgr/Elsewhere.spd.xml");
  std::ofstream(dcd, std::ios::trunc) << text;

  ProfileLoader loader(root.path());
  auto node = loader.load_node(dcd);
  INFO((node ? std::string() : node.error().to_string()));
  REQUIRE(node.has_value());
  CHECK_THAT(warning_at(node->tolerated, "missing-file", 5).message,
             Contains("rsca-noded is the DeviceManager"));
}

TEST_CASE("an empty entrypoint and an empty processor name are read", "[redhawk22][spd]") {
  ProfileLoader loader(kRoot);
  auto pkg = loader.load_softpkg(kRoot / "dom/components/comp/comp.spd.xml");
  INFO((pkg ? std::string() : pkg.error().to_string()));
  REQUIRE(pkg.has_value());
  const auto &impl = (*pkg)->spd->implementations.front();
  CHECK(impl.code.entrypoint.empty()); // the code's file is what runs
  CHECK(impl.processors.empty());      // an empty name would match no device
  CHECK_THAT(warning_at((*pkg)->warnings, "empty-value", 19).message,
             Contains("<processor> with no name"));
}

TEST_CASE("REDHAWK 3 child packages and a package without implementation are read",
          "[redhawk22][spd]") {
  ProfileLoader loader(kRoot);
  auto pkg = loader.load_softpkg(kRoot / "dev/devices/child/child.spd.xml");
  REQUIRE(pkg.has_value());
  CHECK((*pkg)->spd->implementations.empty());
  CHECK(warning_at((*pkg)->warnings, "not-modelled", 8).where.column == 23);
  CHECK_THAT(warning_at((*pkg)->warnings, "no-implementation", 3).message,
             Contains("nothing of it can run"));
}

TEST_CASE("a missing PRF makes its package unavailable, not invalid", "[redhawk22][missing-file]") {
  ProfileLoader loader(kRoot);
  const ResolvedApplication app = load_app(loader, "missing.sad.xml");
  const auto &pkg = *app.component_files.at("nothing_spd");
  REQUIRE(pkg.unavailable.size() == 1);
  check(pkg.unavailable.front(), "missing-file", file_of("dom/components/nothing/nothing.spd.xml"),
        8, 40, {"nothing.prf.xml"});
  CHECK(app.warnings.empty());
  warning_at(app.tolerated, "missing-file", 8);
}
