// REDHAWK's own profiles (the read-only corpus SDR root): every file validates, every
// application resolves with its components and shared libraries, and the values and findings
// are the ones the files hold.
#include "profile/descriptor.hpp"
#include "profile/profile_loader.hpp"
#include "profile/property_binding.hpp"
#include "profile/sdr_root.hpp"
#include "temp_dir.hpp"
#include "test_files.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <complex>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <variant>
#include <vector>

using namespace rsca;
using namespace rsca::profile;
using Catch::Matchers::Contains;
using Catch::Matchers::EndsWith;
using rsca::test::kCorpus;
using rsca::test::TempDir;

namespace fs = std::filesystem;

namespace {

const fs::path kWaveforms = kCorpus / "dom/waveforms/rh";

fs::path waveform(const std::string &name) {
  return kWaveforms / name / (name + ".sad.xml");
}

// Every profile of the corpus, sorted so failures list in a stable order.
std::vector<fs::path> corpus_profiles() {
  std::vector<fs::path> files;
  for (const auto &entry : fs::recursive_directory_iterator(kCorpus))
    if (entry.is_regular_file() && entry.path().extension() == ".xml")
      files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

// The six applications with their number of component files and of instances.
struct Waveform {
  std::string name;
  std::size_t component_files;
  std::size_t instances;
};
const std::vector<Waveform> kApplications = {
    {"FM_RBDS_demo", 6, 7},          {"FM_mono_demo", 5, 6},
    {"basic_components_demo", 5, 6}, {"short_file_to_float_file", 3, 3},
    {"socket_loopback_demo", 3, 3},  {"vita49_loopback_demo", 3, 3}};

ResolvedApplication load(ProfileLoader &loader, const fs::path &sad) {
  INFO(sad.string());
  auto app = loader.load_application(sad);
  if (!app)
    FAIL("load_application failed:\n" << app.error().to_string());
  return std::move(*app);
}

std::size_t instance_count(const SoftwareAssembly &sad) {
  std::size_t n = 0;
  for (const auto &p : sad.placements)
    n += p.instantiations.size();
  return n;
}

// Checks every softpkg dependency below `pkg` is resolved (and its implref exists); returns the
// names of all packages reached, `pkg` excluded.
std::set<std::string> dependencies_of(const ResolvedSoftPkg &pkg) {
  std::set<std::string> names;
  std::function<void(const ResolvedSoftPkg &)> walk = [&](const ResolvedSoftPkg &p) {
    REQUIRE(p.implementations.size() == p.spd->implementations.size());
    for (const auto &impl : p.implementations) {
      REQUIRE(impl.implementation != nullptr);
      REQUIRE(impl.dependencies.size() == impl.implementation->softpkg_dependencies.size());
      for (const auto &dep : impl.dependencies) {
        INFO(p.spd->name << " implementation " << impl.implementation->id);
        REQUIRE(dep.softpkg != nullptr);
        REQUIRE(dep.softpkg->spd != nullptr);
        if (dep.implref)
          CHECK(dep.softpkg->spd->find_implementation(*dep.implref) != nullptr);
        names.insert(dep.softpkg->spd->name);
        walk(*dep.softpkg);
      }
    }
  };
  walk(pkg);
  return names;
}

const ResolvedSoftPkg &softpkg_named(const ResolvedApplication &app, std::string_view name) {
  for (const auto &[id, pkg] : app.component_files)
    if (pkg->spd->name == name)
      return *pkg;
  FAIL("no component " << name);
  throw;
}

// The overrides of instance `id`, each bound to its PRF definition, by property id.
std::map<std::string, PropertyValue> bound_overrides(const ResolvedApplication &app,
                                                     std::string_view id) {
  const ComponentPlacement *placement = nullptr;
  const ComponentInstantiation *ci = app.sad->find_instantiation(id, &placement);
  REQUIRE(ci != nullptr);
  const ResolvedSoftPkg *pkg = app.softpkg_of(*placement);
  REQUIRE(pkg != nullptr);
  std::map<std::string, PropertyValue> values;
  for (const auto &ref : ci->properties) {
    INFO(id << " property " << refid_of(ref));
    const PropertyDefinition *definition = pkg->find_property(refid_of(ref));
    REQUIRE(definition != nullptr);
    auto bound = bind_property(*definition, ref);
    if (!bound)
      FAIL(bound.error().to_string());
    values.emplace(refid_of(ref), std::move(*bound));
  }
  return values;
}

template <typename T>
T scalar_as(const PropertyValue &value) {
  const Scalar *scalar = std::get_if<Scalar>(&value);
  REQUIRE(scalar != nullptr);
  const T *typed = std::get_if<T>(scalar);
  REQUIRE(typed != nullptr);
  return *typed;
}

template <typename T>
T member_as(const PropertyValue &value, std::string_view member) {
  const StructValue *s = std::get_if<StructValue>(&value);
  REQUIRE(s != nullptr);
  for (const auto &[id, v] : s->members)
    if (id == member)
      return scalar_as<T>(std::get<Scalar>(v));
  FAIL("no member " << member);
  throw;
}

} // namespace

TEST_CASE("every corpus profile validates", "[corpus]") {
  const auto files = corpus_profiles();
  CHECK(files.size() == 89);
  ProfileLoader loader;
  std::vector<std::string> failures;
  std::vector<std::string> warned;
  std::map<DescriptorType, int> by_type;
  for (const auto &file : files) {
    const auto validated = loader.validate(file);
    if (!validated) {
      failures.push_back(validated.error().to_string());
      continue;
    }
    ++by_type[type_of(validated->descriptor)];
    if (!validated->warnings.empty())
      warned.push_back(file.filename().string());
  }
  INFO("failures:\n" << Catch::Detail::stringify(failures));
  CHECK(failures.empty());
  CHECK(warned == std::vector<std::string>{"short_file_to_float_file.sad.xml"});
  CHECK(by_type[DescriptorType::SAD] == 6);
  CHECK(by_type[DescriptorType::SPD] == 31);
  CHECK(by_type[DescriptorType::SCD] == 26);
  CHECK(by_type[DescriptorType::PRF] == 26);
}

TEST_CASE("all six applications load with every package resolved", "[corpus][loader]") {
  ProfileLoader loader;
  for (const auto &w : kApplications) {
    INFO(w.name);
    const ResolvedApplication app = load(loader, waveform(w.name));
    CHECK(app.sad->component_files.size() == w.component_files);
    CHECK(app.component_files.size() == app.sad->component_files.size());
    CHECK(instance_count(*app.sad) == w.instances);
    for (const auto &cf : app.sad->component_files) {
      INFO("component file " << cf.id);
      const auto it = app.component_files.find(cf.id);
      REQUIRE(it != app.component_files.end());
      const ResolvedSoftPkg &pkg = *it->second;
      CHECK(pkg.scd != nullptr);
      CHECK(pkg.properties != nullptr);
      CHECK(fs::exists(pkg.spd_path));
      dependencies_of(pkg);
    }
    for (const auto &placement : app.sad->placements)
      CHECK(app.softpkg_of(placement) != nullptr);
  }
}

TEST_CASE("softpkg dependencies resolve transitively", "[corpus][loader][deps]") {
  ProfileLoader loader;
  const ResolvedApplication mono = load(loader, waveform("FM_mono_demo"));
  const ResolvedSoftPkg &psd = softpkg_named(mono, "rh.psd");
  CHECK(dependencies_of(psd) == std::set<std::string>{"rh.dsp", "rh.fftlib"});
  CHECK(dependencies_of(softpkg_named(mono, "rh.ArbitraryRateResampler")) ==
        std::set<std::string>{"rh.dsp"});

  // fftlib needs dsp itself, so DataConverter, which names only fftlib, reaches both.
  const ResolvedApplication shorts = load(loader, waveform("short_file_to_float_file"));
  CHECK(dependencies_of(softpkg_named(shorts, "rh.DataConverter")) ==
        std::set<std::string>{"rh.dsp", "rh.fftlib"});
  CHECK(dependencies_of(softpkg_named(shorts, "rh.FileReader")) ==
        std::set<std::string>{"rh.RedhawkDevUtils", "rh.blueFileLib"});

  const ResolvedApplication vita = load(loader, waveform("vita49_loopback_demo"));
  CHECK(dependencies_of(softpkg_named(vita, "rh.SinkVITA49")) ==
        std::set<std::string>{"rh.VITA49"});
  CHECK(dependencies_of(softpkg_named(vita, "rh.SigGen")).empty());

  // The loader reads a shared library once: psd's dsp is fftlib's dsp.
  const auto &psd_deps = psd.implementations.at(0).dependencies;
  REQUIRE(psd_deps.size() == 2);
  const auto find_dep = [&](std::string_view name) {
    for (const auto &d : psd_deps)
      if (d.softpkg->spd->name == name)
        return d.softpkg;
    FAIL("psd has no dependency " << name);
    throw;
  };
  const auto dsp = find_dep("rh.dsp");
  const auto fftlib = find_dep("rh.fftlib");
  CHECK(psd_deps[0].implref == std::optional<std::string>("cpp"));
  REQUIRE(fftlib->implementations.at(0).dependencies.size() == 1);
  CHECK(fftlib->implementations[0].dependencies[0].softpkg == dsp);
  CHECK(dsp->scd == nullptr);
  CHECK(dsp->spd->implementations.at(0).code.type == CodeType::SharedLibrary);
}

TEST_CASE("the one wiring finding of the corpus", "[corpus][warnings]") {
  ProfileLoader loader;
  for (const auto &w : kApplications) {
    INFO(w.name);
    const ResolvedApplication app = load(loader, waveform(w.name));
    if (w.name != "short_file_to_float_file") {
      CHECK(app.warnings.empty());
      continue;
    }
    REQUIRE(app.warnings.size() == 1);
    const Diagnostic &d = app.warnings.front();
    CHECK(d.severity == Severity::Warning);
    CHECK(d.rule == "unknown-port");
    CHECK(d.where.line == 80);
    CHECK_THAT(d.where.file, EndsWith("short_file_to_float_file.sad.xml"));
    CHECK_THAT(d.message, Contains("connection \"connection_1\"") && Contains("DataConverter_1") &&
                              Contains("\"dataShort\"") && Contains("dataShort_in"));
  }
}

TEST_CASE("FM_mono_demo overrides bind to typed values", "[corpus][binding]") {
  ProfileLoader loader;
  const ResolvedApplication app = load(loader, waveform("FM_mono_demo"));

  const auto narrowband = bound_overrides(app, "narrowband_psd");
  REQUIRE(narrowband.size() == 2);
  CHECK(scalar_as<std::uint32_t>(narrowband.at("fftSize")) == 8192u);
  CHECK(scalar_as<std::uint32_t>(narrowband.at("numAvg")) == 5u);
  const auto fm_psd = bound_overrides(app, "fm_psd");
  CHECK(scalar_as<std::uint32_t>(fm_psd.at("numAvg")) == 20u);

  const auto tfd = bound_overrides(app, "TuneFilterDecimate_1");
  REQUIRE(tfd.size() == 3);
  CHECK(member_as<double>(tfd.at("filterProps"), "Ripple") == 0.5);
  CHECK(std::get<StructValue>(tfd.at("filterProps")).members.size() == 1);
  CHECK(scalar_as<float>(tfd.at("FilterBW")) == 256500.0f);
  CHECK(scalar_as<float>(tfd.at("DesiredOutputRate")) == 256500.0f);

  const auto fastfilter = bound_overrides(app, "fastfilter_1");
  const PropertyValue &filter = fastfilter.at("filterProps");
  CHECK(member_as<std::string>(filter, "Type") == "lowpass");
  CHECK(member_as<double>(filter, "Ripple") == 0.5);
  CHECK(member_as<double>(filter, "freq1") == 16000.0);

  CHECK(scalar_as<float>(bound_overrides(app, "ArbitraryRateResampler_1").at("outputRate")) ==
        32000.0f);
  CHECK(scalar_as<double>(bound_overrides(app, "AmFmPmBasebandDemod_1").at("freqDeviation")) ==
        15000.0);
}

TEST_CASE("FM_RBDS_demo publishes to an event channel", "[corpus][eventchannel]") {
  ProfileLoader loader;
  const ResolvedApplication app = load(loader, waveform("FM_RBDS_demo"));
  std::vector<const Connection *> channel;
  for (const auto &c : app.sad->connections)
    if (c.publishes_to_channel() || c.subscribes_to_channel())
      channel.push_back(&c);
  REQUIRE(channel.size() == 1);
  const Connection &c = *channel.front();
  CHECK(c.id == "connection_22");
  CHECK(c.publishes_to_channel());
  CHECK_FALSE(c.subscribes_to_channel());
  CHECK(c.provides.target.findby.name == "RBDS_Channel");
  CHECK(c.provides.target.findby.type == "eventchannel");
  CHECK(c.uses.port == "messageEvent_out");
  CHECK(c.uses.target.refid == "RBDSDecoder_1");
  CHECK_FALSE(c.filter.has_value());
}

TEST_CASE("the SDR root is found from a file's location", "[corpus][sdrroot]") {
  const auto from_sad = SdrRoot::find_for(waveform("FM_mono_demo"));
  REQUIRE(from_sad.has_value());
  CHECK(from_sad->path() == kCorpus);
  const auto from_device = SdrRoot::find_for(kCorpus / "dev/devices/rh/RTL2832U/RTL2832U.spd.xml");
  REQUIRE(from_device.has_value());
  CHECK(from_device->path() == kCorpus);

  const SdrRoot &root = *from_sad;
  const fs::path spd = kCorpus / "dom/components/rh/psd/psd.spd.xml";
  CHECK(root.resolve("/components/rh/psd/psd.spd.xml", waveform("FM_mono_demo"), SdrTree::Dom) ==
        spd);
  CHECK(root.resolve("/devices/rh/MSDD/MSDD.spd.xml", spd, SdrTree::Dev) ==
        kCorpus / "dev/devices/rh/MSDD/MSDD.spd.xml");
  CHECK(root.resolve("psd.prf.xml", spd, SdrTree::Dom) == spd.parent_path() / "psd.prf.xml");
  CHECK(root.resolve("../fastfilter/fastfilter.spd.xml", spd, SdrTree::Dom) ==
        kCorpus / "dom/components/rh/fastfilter/fastfilter.spd.xml");
}

TEST_CASE("an explicit SDR root overrides the file's location", "[corpus][sdrroot][loader]") {
  // A SAD outside any SDR root loads against the corpus when told so.
  TempDir dir;
  const fs::path copy = dir.path() / "FM_mono_demo.sad.xml";
  fs::copy_file(waveform("FM_mono_demo"), copy);
  ProfileLoader corpus_loader(kCorpus);
  const ResolvedApplication app = load(corpus_loader, copy);
  CHECK(app.component_files.size() == 5);
  CHECK(app.sad_path == copy.lexically_normal());
  CHECK(app.warnings.empty());

  // The corpus SAD against the project's root: its components are not there. As in REDHAWK that
  // is an error only when one is needed (at launch): here each is unavailable, with a warning.
  ProfileLoader own_loader(fs::path(RSCA_SOURCE_DIR) / "profiles");
  const auto read = own_loader.load_application(waveform("FM_mono_demo"));
  REQUIRE(read.has_value());
  for (const auto &[id, pkg] : read->component_files)
    CHECK(pkg->unavailable.size() == 1);
  std::vector<Diagnostic> diagnostics;
  for (const auto &d : read->tolerated)
    if (d.rule == "missing-file")
      diagnostics.push_back(d);
  REQUIRE(diagnostics.size() == 5);
  CHECK(diagnostics[0].where.line == 26);
  CHECK_THAT(diagnostics[0].message,
             Contains((fs::path(RSCA_SOURCE_DIR) / "profiles/dom/components/rh/TuneFilterDecimate")
                          .lexically_normal()
                          .string()));
}

TEST_CASE("a file outside any SDR root has none", "[corpus][sdrroot]") {
  TempDir dir;
  const fs::path copy = dir.path() / "FM_mono_demo.sad.xml";
  fs::copy_file(waveform("FM_mono_demo"), copy);
  const auto root = SdrRoot::find_for(copy);
  CHECK_FALSE(root.has_value());
  ProfileLoader loader;
  const auto app = loader.load_application(copy);
  REQUIRE_FALSE(app.has_value());
  CHECK(app.error().diagnostics().front().rule == "sdrroot");
}
