// The domain's FileManager (domain/file_manager.hpp): the package of a component names its
// profiles, runtime model and code by their path in the repository and their content hash, finds
// code the install did not carry in the exec path, and serves file.read of exactly those files,
// by hash, in bounded pieces, refusing one that changed since it was hashed. What it delivers of
// code (domain/delivered_code.hpp): an ELF executable with debug sections is served without them,
// its full file kept by build id; pieces travel as zstd frames when the node asks; a file that is
// not ELF is served as it is; and --delivery as-is serves the files themselves, uncompressed.
#include "domain/file_manager.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <fstream>

#include <fmt/format.h>

#include "content/elf_facts.hpp"
#include "content/sha256.hpp"
#include "content/zstd.hpp"
#include "profile/runtime_model.hpp"
#include "temp_dir.hpp"

using namespace rsca;
using Catch::Matchers::Contains;
namespace fs = std::filesystem;

namespace {

const fs::path kProducerProfiles = fs::path(RSCA_SOURCE_DIR) / "profiles/dom/components/Producer";

void write(const fs::path &file, const std::string &text) {
  fs::create_directories(file.parent_path());
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out << text;
}

// A repository with the Producer's profiles installed and a code file in an exec path folder.
struct Repository {
  test::TempDir dir;
  fs::path root = dir.path() / "repository";
  fs::path component = root / "applications/A/dom/components/Producer";
  fs::path bin = dir.path() / "bin";
  std::shared_ptr<const profile::ResolvedSoftPkg> softpkg;

  Repository() {
    fs::create_directories(component);
    for (const char *name : {"Producer.spd.xml", "Producer.prf.xml", "Producer.scd.xml"})
      fs::copy_file(kProducerProfiles / name, component / name);
    write(bin / "rsca-producer", std::string(3 * 1024 * 1024 + 17, 'p'));
    fs::permissions(bin / "rsca-producer", fs::perms(0755));
    profile::ProfileLoader loader;
    auto loaded = loader.load_softpkg(component / "Producer.spd.xml");
    REQUIRE(loaded.has_value());
    softpkg = *loaded;
    REQUIRE(profile::write_runtime_model(*softpkg).has_value());
  }
  domain::PackagedComponent producer() const {
    return {"Producer_1", softpkg.get(), softpkg->implementations.at(0).implementation};
  }
};

const protocol::PackageFile *file_named(const protocol::Package &p, const std::string &path) {
  auto it =
      std::find_if(p.files.begin(), p.files.end(), [&](const auto &f) { return f.path == path; });
  return it == p.files.end() ? nullptr : &*it;
}

// The Producer's executable in its package.
const protocol::PackageFile *code_of(const protocol::Package &p) {
  return file_named(p, "applications/A/dom/components/Producer/rsca-producer");
}

// A program of this build, with its debug sections (RelWithDebInfo).
const fs::path kBuilt = RSCA_TEST_FORKED;

// The Producer's code in `repo`'s exec path replaced by `code`; its entry in a new package.
protocol::PackageFile code_as(Repository &repo, domain::FileManager &files, const fs::path &code) {
  if (!code.empty())
    fs::copy_file(code, repo.bin / "rsca-producer", fs::copy_options::overwrite_existing);
  auto package = files.package_of({repo.producer()});
  REQUIRE(package.has_value());
  REQUIRE(code_of(*package) != nullptr);
  return *code_of(*package);
}

// The whole file as a node fetches it, decompressing what comes compressed.
std::string fetch(domain::FileManager &files, const protocol::PackageFile &code, bool zstd) {
  std::string whole;
  for (std::uint64_t offset = 0; offset < code.size; offset += protocol::file::kMaxReadBytes) {
    const auto length = std::min(protocol::file::kMaxReadBytes, code.size - offset);
    auto piece = files.read({code.sha256, offset, protocol::file::kMaxReadBytes, "L1",
                             zstd ? std::optional<std::string>("zstd") : std::nullopt});
    REQUIRE(piece.has_value());
    REQUIRE(piece->payload.has_value());
    if (!piece->compression) {
      whole.append(piece->payload->begin(), piece->payload->end());
      continue;
    }
    REQUIRE(*piece->compression == "zstd");
    auto plain = content::zstd_decompress(piece->payload->data(), piece->payload->size(), length,
                                          protocol::file::kMaxReadBytes);
    REQUIRE(plain.has_value());
    whole.append(plain->begin(), plain->end());
  }
  return whole;
}

} // namespace

TEST_CASE("file manager: a component's package names its profiles, model and code in the "
          "repository's layout",
          "[package]") {
  Repository repo;
  domain::FileManager files(repo.root, {repo.bin});
  auto package = files.package_of({repo.producer()});
  REQUIRE(package.has_value());
  CHECK_FALSE(protocol::package_problem(*package).has_value());
  const std::string dir = "applications/A/dom/components/Producer/";
  for (const char *name :
       {"Producer.spd.xml", "Producer.prf.xml", "Producer.scd.xml", "Producer.spd.xml.model.json"})
    CHECK(file_named(*package, dir + name) != nullptr);
  const auto *code = file_named(*package, dir + "rsca-producer");
  REQUIRE(code != nullptr);
  CHECK(code->executable);
  CHECK(code->size == 3 * 1024 * 1024 + 17);
  CHECK(code->sha256 == content::sha256_of_file(repo.bin / "rsca-producer").value());
  CHECK(package->origin == fs::weakly_canonical(repo.root).string());
}

TEST_CASE("file manager: the code folders of shared-library dependencies are the package's "
          "library folders",
          "[package]") {
  Repository repo;
  // The Producer depends on a library softpkg with a code file and on one with a code folder.
  const fs::path dom = repo.root / "applications/A/dom";
  const auto dependency_spd = [](const std::string &name, const std::string &code) {
    return fmt::format(R"(<?xml version="1.0" encoding="UTF-8"?>
<softpkg id="DCE:{0}" name="{0}">
  <author><name>rsca</name></author>
  <implementation id="cpp">
    <code type="SharedLibrary"><localfile name="{1}"/></code>
    <os name="Linux"/>
  </implementation>
</softpkg>
)",
                       name, code);
  };
  write(dom / "deps/mathlib/mathlib.spd.xml", dependency_spd("mathlib", "lib/libmath.so"));
  write(dom / "deps/mathlib/lib/libmath.so", "ELF?");
  write(dom / "deps/plugins/plugins.spd.xml", dependency_spd("plugins", "plugins"));
  write(dom / "deps/plugins/plugins/a.so", "ELF a");
  write(dom / "deps/plugins/plugins/b.so", "ELF b");
  const fs::path spd = repo.component / "Producer.spd.xml";
  std::ifstream in(spd);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string depends = R"(<dependency type="runtime_requirements"><softpkgref>
      <localfile name="/deps/mathlib/mathlib.spd.xml"/></softpkgref></dependency>
    <dependency type="runtime_requirements"><softpkgref>
      <localfile name="/deps/plugins/plugins.spd.xml"/></softpkgref></dependency>
    )";
  const auto end = text.find("<resourcedemand"); // dependencies come before it
  REQUIRE(end != std::string::npos);
  text.insert(end, depends);
  write(spd, text);
  profile::ProfileLoader loader;
  auto softpkg = loader.load_softpkg(spd);
  INFO((softpkg ? std::string() : softpkg.error().to_string()));
  REQUIRE(softpkg.has_value());

  domain::FileManager files(repo.root, {repo.bin});
  auto package = files.package_of(
      {{"Producer_1", softpkg->get(), (*softpkg)->implementations.at(0).implementation}});
  REQUIRE(package.has_value());
  CHECK_FALSE(protocol::package_problem(*package).has_value());
  CHECK(package->library_dirs ==
        std::vector<std::string>{"applications/A/dom/deps/mathlib/lib",
                                 "applications/A/dom/deps/plugins/plugins"});
  CHECK(file_named(*package, "applications/A/dom/deps/plugins/plugins/b.so") != nullptr);
  // The component's own code (an executable) is no library folder.
  auto alone = files.package_of({repo.producer()});
  REQUIRE(alone.has_value());
  CHECK(alone->library_dirs.empty());
}

TEST_CASE("file manager: code found nowhere fails the package, naming the component and the file",
          "[package]") {
  Repository repo;
  domain::FileManager files(repo.root, {repo.dir.path() / "empty"});
  auto package = files.package_of({repo.producer()});
  REQUIRE_FALSE(package.has_value());
  CHECK(package.error().status == protocol::Status::Failed);
  CHECK_THAT(package.error().message, Contains("Producer_1") && Contains("rsca-producer"));
}

TEST_CASE("file manager: file.read serves the files of packages by hash, in bounded pieces",
          "[package]") {
  Repository repo;
  domain::FileManager files(repo.root, {repo.bin});
  auto package = files.package_of({repo.producer()});
  REQUIRE(package.has_value());
  const auto *code = code_of(*package);
  REQUIRE(code != nullptr);
  std::string whole;
  for (std::uint64_t offset = 0; offset < code->size; offset += protocol::file::kMaxReadBytes) {
    auto piece = files.read({code->sha256, offset, protocol::file::kMaxReadBytes, "L1", {}});
    REQUIRE(piece.has_value());
    CHECK(piece->size == code->size);
    REQUIRE(piece->payload.has_value());
    whole.append(piece->payload->begin(), piece->payload->end());
  }
  CHECK(content::sha256_hex(whole) == code->sha256);
  CHECK(files.delivered("L1").bytes == code->size);
  CHECK(files.delivered("L1").wire_bytes == code->size); // the node asked for no compression
  CHECK(files.delivered("another").bytes == 0);

  // More than a piece, past the end, a hash it never put into a package, not a hash at all.
  CHECK(files.read({code->sha256, 0, protocol::file::kMaxReadBytes + 1, {}, {}}).error().status ==
        protocol::Status::BadRequest);
  CHECK(files.read({code->sha256, code->size + 1, 10, {}, {}}).error().status ==
        protocol::Status::BadRequest);
  CHECK(files.read({content::sha256_hex("/etc/shadow"), 0, 10, {}, {}}).error().status ==
        protocol::Status::NotFound);
  CHECK(files.read({"../../etc/passwd", 0, 10, {}, {}}).error().status ==
        protocol::Status::BadRequest);
}

TEST_CASE("file manager: a file changed since it was put into a package is not served",
          "[package]") {
  Repository repo;
  domain::FileManager files(repo.root, {repo.bin});
  auto package = files.package_of({repo.producer()});
  REQUIRE(package.has_value());
  const auto *code = code_of(*package);
  REQUIRE(code != nullptr);
  write(repo.bin / "rsca-producer", "a new build");
  auto piece = files.read({code->sha256, 0, 10, {}, {}});
  REQUIRE_FALSE(piece.has_value());
  CHECK_THAT(piece.error().message, Contains("changed since"));
  // The next package has the new file's hash.
  auto next = files.package_of({repo.producer()});
  REQUIRE(next.has_value());
  CHECK(file_named(*next, code->path)->sha256 == content::sha256_hex("a new build"));
}

TEST_CASE("file manager: past the files it remembers it forgets the least recently used, never "
          "those of the package it just made",
          "[package]") {
  Repository repo;
  domain::FileManager files(repo.root, {repo.bin});
  // The code is a folder (as REDHAWK allows): 3000 files, then 3000 others, 6000 hashed in all.
  auto fill = [&](char which) {
    fs::remove_all(repo.bin / "rsca-producer");
    for (int i = 0; i < 3000; ++i)
      write(repo.bin / "rsca-producer" / fmt::format("f{}{}", which, i),
            fmt::format("{}{}", which, i));
  };
  fill('a');
  REQUIRE(files.package_of({repo.producer()}).has_value());
  fill('b');
  auto second = files.package_of({repo.producer()});
  REQUIRE(second.has_value());
  for (const auto &f : second->files) {
    INFO(f.path);
    REQUIRE(files.read({f.sha256, 0, 16, {}, {}}).has_value());
  }
}

TEST_CASE("delivered code: an executable with debug sections is served without them, compressed, "
          "its full file kept by build id",
          "[package][delivery]") {
  const auto built = content::elf_facts(kBuilt);
  REQUIRE(built.has_value());
  REQUIRE_FALSE(built->debug_sections.empty()); // a build with debug information
  REQUIRE(built->build_id.has_value());
  Repository repo;
  domain::FileManager files(repo.root, {repo.bin});
  const auto code = code_as(repo, files, kBuilt);
  CHECK(code.executable);
  CHECK(code.size < fs::file_size(kBuilt));

  const std::string whole = fetch(files, code, true);
  CHECK(whole.size() == code.size);
  CHECK(content::sha256_hex(whole) == code.sha256);
  CHECK(files.delivered("L1").bytes == code.size);
  CHECK(files.delivered("L1").wire_bytes < code.size); // compressed
  // What was served is the build's code (same build id), without a debug section.
  const fs::path served = repo.dir.path() / "served";
  {
    std::ofstream out(served, std::ios::binary);
    out << whole;
  }
  const auto facts = content::elf_facts(served);
  REQUIRE(facts.has_value());
  CHECK(facts->debug_sections.empty());
  CHECK(facts->build_id == built->build_id);
  // The full file, where gdb looks for the build id's debug information.
  const auto &id = *built->build_id;
  const fs::path debug = repo.root / ".build-id" / id.substr(0, 2) / (id.substr(2) + ".debug");
  REQUIRE(fs::exists(debug));
  CHECK(content::sha256_of_file(debug).value() == content::sha256_of_file(kBuilt).value());

  // Another launch: the same copy, not stripped again.
  CHECK(code_as(repo, files, {}) == code);
  // A domain that starts again removes the copies it served, and makes them again.
  domain::FileManager restarted(repo.root, {repo.bin});
  CHECK_FALSE(fs::exists(repo.root / ".delivered" / code.sha256));
  CHECK(code_as(repo, restarted, {}) == code);
  CHECK(fs::exists(repo.root / ".delivered" / code.sha256));
}

TEST_CASE("delivered code: a file that is not ELF is served as it is and --delivery as-is serves "
          "the build's file itself uncompressed",
          "[package][delivery]") {
  SECTION("not ELF") {
    test::TempDir dir;
    const fs::path script = dir.path() / "run.sh";
    {
      std::ofstream out(script);
      out << "#!/bin/sh\necho hi\n";
    }
    CHECK_FALSE(content::elf_facts(script).has_value());
    Repository repo;
    domain::FileManager files(repo.root, {repo.bin});
    const auto code = code_as(repo, files, script);
    CHECK(code.sha256 == content::sha256_of_file(script).value());
    CHECK(fetch(files, code, true) == "#!/bin/sh\necho hi\n");
  }
  SECTION("as-is") {
    Repository repo;
    domain::FileManager files(repo.root, {repo.bin}, domain::CodeDelivery::AsIs);
    const auto code = code_as(repo, files, kBuilt);
    CHECK(code.size == fs::file_size(kBuilt));
    CHECK(code.sha256 == content::sha256_of_file(kBuilt).value());
    CHECK(content::sha256_hex(fetch(files, code, true)) == code.sha256);
    CHECK(files.delivered("L1").wire_bytes == code.size); // never compressed
    CHECK_FALSE(fs::exists(repo.root / ".build-id"));
  }
}
