// The InstalledRepository: whatever name or path a client sends, it acts only inside its own
// folder, and an install that fails leaves the repository as it was.
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>

#include <catch2/catch.hpp>

#include "content/base64.hpp"
#include "domain/installed_repository.hpp"

namespace fs = std::filesystem;
using rsca::control::Status;
using rsca::domain::DomainStore;
using rsca::domain::InstalledRepository;
using rsca::domain::InstallRequest;
using rsca::protocol::domain::FileEncoding;

namespace {

const fs::path kTestSdr = fs::path(RSCA_TEST_DATA_DIR) / "integration";

std::string read(const fs::path &file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The install request the CLI sends for an application of the test SDR root.
InstallRequest request_for(const std::string &application) {
  rsca::profile::ProfileLoader loader(kTestSdr);
  auto app = loader.load_application(kTestSdr / "dom/waveforms" / application /
                                     (application + ".sad.xml"));
  REQUIRE(app.has_value());
  InstallRequest request;
  request.sad = app->sad_path.lexically_relative(kTestSdr).string();
  for (const auto &f : app->files())
    request.files.push_back({f.lexically_relative(kTestSdr).string(), read(f), {}, {}});
  return request;
}

// Every file and folder under `dir` (its path relative to `dir`) with a file's content, but the
// store's files, which a request may write to.
std::map<std::string, std::string> tree_of(const fs::path &dir) {
  std::map<std::string, std::string> tree;
  for (const auto &e : fs::recursive_directory_iterator(dir)) {
    const auto name = e.path().filename().string();
    if (name.rfind("domain.sqlite", 0) == 0)
      continue;
    tree[e.path().lexically_relative(dir).string()] =
        e.is_regular_file() ? read(e.path()) : std::string("(folder)");
  }
  return tree;
}

// A folder with a repository (and its store) inside, and a victim where each name or path a
// test sends would land if it escaped: the installs' folder is root/applications, so
// "../victim" lands in root, "../../victim" beside root. Removed with it.
struct Sandbox {
  fs::path top = fs::temp_directory_path() / ("rsca-repository-test-" + std::to_string(::getpid()) +
                                              "-" + std::to_string(std::random_device{}()));
  fs::path root = top / "a/b/repository";
  std::vector<fs::path> victims = {root / "victim", root.parent_path() / "victim",
                                   root.parent_path().parent_path() / "victim"};
  std::optional<DomainStore> store;
  std::optional<InstalledRepository> repository;

  Sandbox() {
    fs::create_directories(root);
    for (const auto &victim : victims) {
      fs::create_directories(victim);
      std::ofstream(victim / "precious") << "keep me";
    }
    open();
  }
  ~Sandbox() {
    repository.reset();
    store.reset();
    std::error_code ignored;
    fs::remove_all(top, ignored);
  }
  Sandbox(const Sandbox &) = delete;
  Sandbox &operator=(const Sandbox &) = delete;

  void open() {
    repository.reset();
    store.reset();
    auto s = DomainStore::open(root / "domain.sqlite");
    REQUIRE(s.has_value());
    store.emplace(std::move(*s));
    repository.emplace(root, *store);
    repository->load();
  }
  bool victim_intact() const {
    return std::all_of(victims.begin(), victims.end(), [](const fs::path &victim) {
      return read(victim / "precious") == "keep me" && tree_of(victim).size() == 1;
    });
  }
  // Everything in the sandbox, in and around the repository, but the store.
  std::map<std::string, std::string> tree() const { return tree_of(top); }
  // Folders or files in the repository other than the store and the installs.
  std::vector<std::string> leftovers() const {
    std::vector<std::string> found;
    if (!fs::exists(root / ".staging"))
      return found;
    for (const auto &e : fs::recursive_directory_iterator(root / ".staging")) {
      found.push_back(e.path().string());
    }
    return found;
  }
};

} // namespace

TEST_CASE("an install name that is a path is refused and nothing outside the repository changes",
          "[unit][installed-repository]") {
  Sandbox box;
  const auto before = box.tree();
  for (const std::string name : {"../../victim", "../victim", ".", "..", "a/b", ""}) {
    INFO(name);
    auto request = request_for("Healthy");
    request.name = name;
    auto installed = box.repository->install(request);
    REQUIRE_FALSE(installed.has_value());
    CHECK(installed.error().status == Status::BadRequest);
    CHECK(box.victim_intact());
    CHECK(fs::exists(box.root / "domain.sqlite"));
  }
  CHECK(box.repository->list().empty());
  for (const std::string name : {"../../victim", "..", "."}) {
    INFO(name);
    auto removed = box.repository->uninstall(name);
    REQUIRE_FALSE(removed.has_value());
    CHECK(removed.error().status == Status::BadRequest);
    CHECK(box.victim_intact());
    CHECK(fs::exists(box.root / "domain.sqlite"));
  }
  CHECK(box.tree() == before); // nothing anywhere changed, inside the repository or out
}

TEST_CASE("an install goes into a folder of its own and its uninstall removes only that",
          "[unit][installed-repository]") {
  Sandbox box;
  auto request = request_for("Healthy");
  request.name = "domain.sqlite"; // a name like the store's file cannot reach it
  auto installed = box.repository->install(request);
  REQUIRE(installed.has_value());
  CHECK(fs::exists(box.root / "applications/domain.sqlite" / request.sad));
  REQUIRE(box.repository->uninstall("domain.sqlite").has_value());
  CHECK_FALSE(fs::exists(box.root / "applications/domain.sqlite"));
  CHECK(fs::is_regular_file(box.root / "domain.sqlite"));
  box.open(); // the store still works and no longer lists it
  CHECK(box.repository->list().empty());
}

TEST_CASE("a failed install leaves no staging copy and keeps what was installed under its name",
          "[unit][installed-repository]") {
  Sandbox box;
  auto good = request_for("Healthy");
  REQUIRE(box.repository->install(good).has_value());
  const auto before = box.repository->find("Healthy");
  REQUIRE(before.has_value());
  const auto tree_before = box.tree();

  SECTION("a profile that does not load") {
    auto broken = good;
    for (auto &f : broken.files)
      if (f.path == broken.sad)
        f.content = "<softwareassembly";
    auto installed = box.repository->install(broken);
    REQUIRE_FALSE(installed.has_value());
    CHECK(installed.error().status == Status::BadRequest);
  }
  SECTION("a file outside the SDR root") {
    auto outside = good;
    outside.files.push_back({"../../escape.xml", "x", {}, {}});
    auto installed = box.repository->install(outside);
    REQUIRE_FALSE(installed.has_value());
    CHECK(installed.error().status == Status::BadRequest);
  }
  SECTION("code whose content is not base64") {
    auto bad = good;
    bad.files.push_back(
        {"dom/components/Healthy/healthy", "not base64!", FileEncoding::Base64, true});
    auto installed = box.repository->install(bad);
    REQUIRE_FALSE(installed.has_value());
    CHECK(installed.error().status == Status::BadRequest);
    CHECK_THAT(installed.error().message, Catch::Contains("not base64"));
  }
  SECTION("more bytes than an install carries") {
    auto big = good;
    const std::string megabyte(1 << 20, 'x');
    for (int i = 0; i < 11; ++i)
      big.files.push_back({"dom/components/big/part" + std::to_string(i),
                           rsca::content::base64_encode(megabyte), FileEncoding::Base64, false});
    auto installed = box.repository->install(big);
    REQUIRE_FALSE(installed.has_value());
    CHECK(installed.error().status == Status::BadRequest);
    CHECK_THAT(installed.error().message, Catch::Contains("at most 10 MiB"));
  }
  SECTION("for a launch, a SAD of the same name that a launch would refuse") {
    auto miswired = request_for("HealthyMiswired");
    miswired.for_launch = true;
    auto installed = box.repository->install(miswired);
    REQUIRE_FALSE(installed.has_value());
    CHECK(installed.error().status == Status::BadRequest);
    // Named as the client's file, relative to its SDR root, not as the staging copy.
    CHECK_THAT(installed.error().message,
               Catch::Contains("dom/waveforms/HealthyMiswired/HealthyMiswired.sad.xml:40:21: "
                               "unknown-port"));
    CHECK_THAT(installed.error().message, !Catch::Contains(".staging"));
  }
  SECTION("a SAD whose name is 7 MB long") {
    auto huge = good;
    const std::string name(7 * 1024 * 1024, 'n');
    for (auto &f : huge.files)
      if (f.path == huge.sad) {
        const auto at = f.content.find("name=\"Healthy\"");
        REQUIRE(at != std::string::npos);
        f.content.replace(at, 14, "name=\"" + name + "\"");
      }
    auto installed = box.repository->install(huge);
    REQUIRE_FALSE(installed.has_value());
    CHECK(installed.error().message.size() < 4096); // a bounded excerpt, not the name
  }
  CHECK(box.leftovers().empty());
  // Nothing written anywhere: an escaped file ("../../escape.xml" from a staging folder lands in
  // the repository's root), a staging copy, a change to the install.
  CHECK(box.tree() == tree_before);
  auto after = box.repository->find("Healthy");
  REQUIRE(after.has_value());
  CHECK(fs::exists(after->sad));
  box.open(); // and after a restart
  CHECK(box.repository->find("Healthy").has_value());
}

TEST_CASE("an application read aside is loaded and leaves nothing in the repository",
          "[unit][installed-repository]") {
  Sandbox box;
  const auto tree_before = box.tree();
  auto app = box.repository->read_aside(request_for("Healthy"));
  REQUIRE(app.has_value());
  CHECK((*app)->sad->name == "Healthy");
  CHECK((*app)->component_files.size() == 2);
  auto escaping = request_for("Healthy");
  escaping.files.push_back({"../../escape.xml", "x", {}, {}});
  auto refused = box.repository->read_aside(escaping);
  REQUIRE_FALSE(refused.has_value());
  CHECK(refused.error().status == Status::BadRequest);
  CHECK(box.leftovers().empty());
  // Nothing else: the staging folder itself stays, empty, as after any install.
  auto tree_after = box.tree();
  tree_after.erase((box.root / ".staging").lexically_relative(box.top).string());
  CHECK(tree_after == tree_before);
  CHECK_FALSE(box.repository->find("Healthy").has_value());
}

TEST_CASE("a store record that points outside the repository is skipped, never acted on",
          "[unit][installed-repository]") {
  Sandbox box;
  // As a vulnerable version could have recorded it.
  REQUIRE(box.store->put_installed({"../../victim", "../../victim/x.sad.xml"}).has_value());
  REQUIRE(box.store->put_installed({"victim", "../victim/x.sad.xml"}).has_value());
  box.open();
  CHECK(box.repository->list().empty());
  CHECK(box.repository->uninstall("victim").error().status == Status::NotFound);
  CHECK(box.victim_intact());
}

TEST_CASE("code carried in base64 is written as its bytes, executable when it was",
          "[unit][installed-repository]") {
  Sandbox box;
  auto request = request_for("Healthy");
  std::string binary;
  for (int i = 0; i < 256; ++i)
    binary.push_back(static_cast<char>(i));
  request.files.push_back({"dom/components/Healthy/healthy", rsca::content::base64_encode(binary),
                           FileEncoding::Base64, true});
  request.files.push_back({"dom/components/Healthy/libhealthy.so",
                           rsca::content::base64_encode("lib"), FileEncoding::Base64, false});
  auto installed = box.repository->install(request);
  REQUIRE(installed.has_value());
  auto found = box.repository->find("Healthy");
  REQUIRE(found.has_value());
  const fs::path dom = found->sad.parent_path().parent_path().parent_path();
  CHECK(read(dom / "components/Healthy/healthy") == binary);
  CHECK(read(dom / "components/Healthy/libhealthy.so") == "lib");
  const auto exec = [](const fs::path &f) {
    return (fs::status(f).permissions() & fs::perms::owner_exec) != fs::perms::none;
  };
  CHECK(exec(dom / "components/Healthy/healthy"));
  CHECK_FALSE(exec(dom / "components/Healthy/libhealthy.so"));
}
