// Runtime models (profile/runtime_model.hpp): every software package of the corpus and of the
// project reads back from its model as it was read from its XML, a model is used only while the
// files it came from are unchanged, and the component loader falls back to the XML otherwise.
#include "profile/runtime_model.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "test_files.hpp"

using namespace rsca::profile;
using Catch::Matchers::Contains;
namespace fs = std::filesystem;
using Json = nlohmann::json;
using rsca::test::kCorpus;

namespace {

const fs::path kOwn = fs::path(RSCA_SOURCE_DIR) / "profiles";

std::vector<fs::path> spds_under(const fs::path &root) {
  std::vector<fs::path> files;
  for (const auto &entry : fs::recursive_directory_iterator(root))
    if (entry.path().string().ends_with(".spd.xml"))
      files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<const PropertyDefinition *> definitions_of(const ResolvedSoftPkg &softpkg) {
  std::vector<const PropertyDefinition *> out;
  auto add = [&out](const std::shared_ptr<const Properties> &prf) {
    if (prf)
      for (const auto &d : prf->properties)
        out.push_back(&d);
  };
  add(softpkg.properties);
  for (const auto &implementation : softpkg.implementations)
    add(implementation.properties);
  return out;
}

std::string default_text(const PropertyDefinition &d) {
  auto value = default_value(d);
  return value ? format_value(*value) : "(none)";
}

// What a component runs on, compared field by field against the package read from its XML.
void check_same(const ResolvedSoftPkg &xml, const ResolvedSoftPkg &model) {
  const auto expected = definitions_of(xml);
  const auto actual = definitions_of(model);
  REQUIRE(actual.size() == expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const auto &e = common_of(*expected[i]);
    const auto &a = common_of(*actual[i]);
    INFO("property " << e.id);
    CHECK(a.id == e.id);
    CHECK(a.mode == e.mode);
    CHECK(a.kinds == e.kinds);
    CHECK(a.where.line == e.where.line);
    CHECK(expected[i]->index() == actual[i]->index());
    CHECK(default_text(*actual[i]) == default_text(*expected[i]));
  }
  REQUIRE(static_cast<bool>(model.scd) == static_cast<bool>(xml.scd));
  if (!xml.scd)
    return;
  REQUIRE(model.scd->ports.size() == xml.scd->ports.size());
  for (const auto &port : xml.scd->ports) {
    const auto *found = model.scd->find_port(port.name, port.direction);
    REQUIRE(found != nullptr);
    CHECK(found->repid == port.repid);
  }
}

// A folder removed with it, also when the test fails while filling it.
struct TemporaryFolder {
  fs::path path;
  explicit TemporaryFolder(fs::path p) : path(std::move(p)) { fs::remove_all(path); }
  ~TemporaryFolder() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
  TemporaryFolder(const TemporaryFolder &) = delete;
  TemporaryFolder &operator=(const TemporaryFolder &) = delete;
};

// A copy of the project's Producer package in an SDR root of its own, with its runtime model.
struct ProducerCopy {
  TemporaryFolder folder{fs::temp_directory_path() /
                         ("rsca-runtime-model-" + std::to_string(::getpid()))};
  fs::path root = folder.path;
  fs::path dir = root / "dom/components/Producer";
  fs::path spd = dir / "Producer.spd.xml";

  ProducerCopy() {
    fs::create_directories(dir);
    for (const auto &entry : fs::directory_iterator(kOwn / "dom/components/Producer"))
      fs::copy_file(entry.path(), dir / entry.path().filename());
    auto softpkg = ProfileLoader().load_softpkg(spd);
    INFO((softpkg ? "" : softpkg.error().to_string()));
    REQUIRE(softpkg.has_value());
    REQUIRE(write_runtime_model(**softpkg).has_value());
  }

  Json model() const { return Json::parse(std::ifstream(runtime_model_path(spd))); }
  void set_model(const Json &json) const { std::ofstream(runtime_model_path(spd)) << json.dump(); }
  // Changes the default of one property in the model only.
  void set_default(const std::string &id, const std::string &value) const {
    Json edited = model();
    for (auto &d : edited["properties"]["definitions"])
      if (d["id"] == id)
        d["value"] = value;
    set_model(edited);
  }
};

const PropertyDefinition *find(const ResolvedSoftPkg &softpkg, const std::string &id) {
  return softpkg.find_property(id);
}

} // namespace

TEST_CASE("every software package reads back from its runtime model as from its XML",
          "[profile][runtime-model]") {
  ProfileLoader loader;
  std::size_t checked = 0;
  for (const auto &root : {kCorpus, kOwn}) {
    for (const auto &spd : spds_under(root)) {
      auto xml = loader.load_softpkg(spd);
      if (!xml && root == kCorpus)
        continue; // the corpus test says which do not load on their own
      INFO((xml ? "" : xml.error().to_string()));
      REQUIRE(xml.has_value());
      INFO(spd.string());
      const Json model = to_runtime_model(**xml);
      auto back = from_runtime_model(model, spd);
      REQUIRE(back.has_value());
      CHECK((*back)->spd_path == spd);
      check_same(**xml, **back);
      // Nothing is lost on the way: the model of what was read back is the same model.
      CHECK(to_runtime_model(**back) == model);
      ++checked;
    }
  }
  CHECK(checked >= 40); // 44 when written: the corpus's and the project's packages
}

TEST_CASE("a component loader uses the runtime model while its sources are unchanged",
          "[profile][runtime-model]") {
  ProducerCopy copy;
  // A default changed in the model only: seen, so the package came from the model.
  copy.set_default("message", "from the model");

  ComponentProfileLoader loader;
  auto softpkg = loader.load(copy.spd);
  REQUIRE(softpkg.has_value());
  CHECK(loader.fallback_reason().empty());
  REQUIRE(find(**softpkg, "message") != nullptr);
  CHECK(default_text(*find(**softpkg, "message")) == "from the model");
  // Read once: a second instance of the package gets the same one, and its reason to read XML
  // is not the last other package's.
  REQUIRE(loader.load(kOwn / "dom/components/Consumer/Consumer.spd.xml").has_value());
  CHECK_THAT(loader.fallback_reason(), Contains("there is none"));
  auto again = loader.load(copy.spd);
  REQUIRE(again.has_value());
  CHECK(again->get() == softpkg->get());
  CHECK(loader.fallback_reason().empty());
}

TEST_CASE("a runtime model older than a file it came from is not used: the XML is read",
          "[profile][runtime-model]") {
  ProducerCopy copy;
  copy.set_default("message", "from the model");
  const std::string changed = GENERATE("Producer.prf.xml", "Producer.scd.xml", "Producer.spd.xml");
  INFO(changed);
  const fs::path file = copy.dir / changed;
  SECTION("its modification time") {
    const auto before = fs::last_write_time(file);
    fs::last_write_time(file, before + std::chrono::seconds(1));
    REQUIRE(fs::last_write_time(file) > before);
  }
  SECTION("its size, at the same modification time") {
    const auto when = fs::last_write_time(file);
    const auto size = fs::file_size(file);
    std::ofstream(file, std::ios::app) << "\n";
    fs::last_write_time(file, when);
    REQUIRE(fs::file_size(file) == size + 1);
    REQUIRE(fs::last_write_time(file) == when);
  }

  auto read = read_runtime_model(copy.spd);
  REQUIRE_FALSE(read.has_value());
  CHECK_THAT(read.error().to_string(), Contains(changed + " changed since it was written"));

  ComponentProfileLoader loader;
  auto softpkg = loader.load(copy.spd);
  REQUIRE(softpkg.has_value());
  CHECK_THAT(loader.fallback_reason(), Contains("changed since it was written"));
  CHECK(default_text(*find(**softpkg, "message")) == "hello"); // the PRF's own default
}

TEST_CASE("a file edited after it was read but before the model was written makes the model stale",
          "[profile][runtime-model]") {
  // The model's stamps are those from before the read: stamps taken when writing would make a
  // model of the old content pass for the new file.
  ProducerCopy copy;
  auto softpkg = ProfileLoader().load_softpkg(copy.spd);
  REQUIRE(softpkg.has_value());
  const fs::path prf = copy.dir / "Producer.prf.xml";
  const auto when = fs::last_write_time(prf);
  std::ofstream(prf, std::ios::app) << "\n"; // the edit, between the read and the write
  fs::last_write_time(prf, when + std::chrono::seconds(1));
  REQUIRE(write_runtime_model(**softpkg).has_value());

  auto read = read_runtime_model(copy.spd);
  REQUIRE_FALSE(read.has_value());
  CHECK_THAT(read.error().to_string(), Contains("Producer.prf.xml changed since it was written"));
}

TEST_CASE("a runtime model copied along with its package is not used for the copy",
          "[profile][runtime-model]") {
  ProducerCopy copy;
  const fs::path elsewhere = copy.root / "dom/components/ProducerCopy";
  fs::copy(copy.dir, elsewhere);
  const fs::path spd = elsewhere / "Producer.spd.xml";
  REQUIRE(fs::exists(runtime_model_path(spd)));
  auto read = read_runtime_model(spd);
  REQUIRE_FALSE(read.has_value());
  CHECK_THAT(read.error().to_string(), Contains("it was written for another SPD"));
}

TEST_CASE("a runtime model relocated into a node's package is used there, by the path a process "
          "started in the package gives",
          "[profile][runtime-model]") {
  ProducerCopy copy;
  // The package as a node lays it out: the domain's files under their path from its origin.
  const fs::path package = copy.root / "package";
  const fs::path inside = fs::path("dom/components/Producer");
  fs::create_directories(package / inside);
  for (const auto &entry : fs::directory_iterator(copy.dir))
    fs::copy_file(entry.path(), package / inside / entry.path().filename());
  const fs::path model = inside / "Producer.spd.xml.model.json";
  REQUIRE(is_runtime_model_path(model));
  REQUIRE(relocate_runtime_model(package, model, copy.root.string()).has_value());
  // The component runs in the package and is given its SPD relative to it.
  const fs::path before = fs::current_path();
  fs::current_path(package);
  auto read = read_runtime_model(inside / "Producer.spd.xml");
  fs::current_path(before);
  INFO((read ? "" : read.error().to_string()));
  CHECK(read.has_value());
  // Not the domain's copy: its model still names its own files.
  CHECK(read_runtime_model(copy.spd).has_value());
}

TEST_CASE("a missing or broken runtime model makes the component loader read the XML",
          "[profile][runtime-model]") {
  ProducerCopy copy;
  SECTION("missing") {
    fs::remove(runtime_model_path(copy.spd));
    ComponentProfileLoader loader;
    REQUIRE(loader.load(copy.spd).has_value());
    CHECK_THAT(loader.fallback_reason(), Contains("there is none"));
  }
  SECTION("not JSON") {
    std::ofstream(runtime_model_path(copy.spd)) << "{ truncated";
    ComponentProfileLoader loader;
    REQUIRE(loader.load(copy.spd).has_value());
    CHECK_THAT(loader.fallback_reason(), Contains("not JSON"));
  }
  SECTION("a value that does not fit its type") {
    copy.set_default("rate_hz", "fast");
    ComponentProfileLoader loader;
    auto softpkg = loader.load(copy.spd);
    REQUIRE(softpkg.has_value());
    CHECK_THAT(loader.fallback_reason(), Contains("fast"));
    CHECK(default_text(*find(**softpkg, "rate_hz")) == "100");
  }
  SECTION("another format") {
    Json model = copy.model();
    model["format"] = 99;
    copy.set_model(model);
    ComponentProfileLoader loader;
    REQUIRE(loader.load(copy.spd).has_value());
    CHECK_THAT(loader.fallback_reason(), Contains("format 99"));
  }
}

TEST_CASE("a runtime model that cannot be written is an error naming it, and nothing is left",
          "[profile][runtime-model]") {
  ProducerCopy copy;
  auto softpkg = ProfileLoader().load_softpkg(copy.spd);
  REQUIRE(softpkg.has_value());
  ResolvedSoftPkg elsewhere = **softpkg;
  elsewhere.spd_path = copy.root / "no such folder" / "Producer.spd.xml";
  auto written = write_runtime_model(elsewhere);
  REQUIRE_FALSE(written.has_value());
  CHECK_THAT(written.error().to_string(), Contains("Producer.spd.xml.model.json"));
  CHECK_THAT(written.error().to_string(), Contains("cannot write"));
  CHECK_FALSE(fs::exists(copy.root / "no such folder"));
}
