// The domain's FileManager (domain/file_manager.hpp): the package of a component names its
// profiles, runtime model and code by their path in the repository and their content hash, finds
// code the install did not carry in the exec path, and serves file.read of exactly those files,
// by hash, in bounded pieces, refusing one that changed since it was hashed.
#include "domain/file_manager.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <fstream>

#include <fmt/format.h>

#include "content/sha256.hpp"
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
    auto piece = files.read({code->sha256, offset, protocol::file::kMaxReadBytes, "L1"});
    REQUIRE(piece.has_value());
    CHECK(piece->size == code->size);
    REQUIRE(piece->payload.has_value());
    whole.append(piece->payload->begin(), piece->payload->end());
  }
  CHECK(content::sha256_hex(whole) == code->sha256);
  CHECK(files.delivered("L1") == code->size);
  CHECK(files.delivered("another") == 0);

  // More than a piece, past the end, a hash it never put into a package, not a hash at all.
  CHECK(files.read({code->sha256, 0, protocol::file::kMaxReadBytes + 1, {}}).error().status ==
        protocol::Status::BadRequest);
  CHECK(files.read({code->sha256, code->size + 1, 10, {}}).error().status ==
        protocol::Status::BadRequest);
  CHECK(files.read({content::sha256_hex("/etc/shadow"), 0, 10, {}}).error().status ==
        protocol::Status::NotFound);
  CHECK(files.read({"../../etc/passwd", 0, 10, {}}).error().status == protocol::Status::BadRequest);
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
  auto piece = files.read({code->sha256, 0, 10, {}});
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
    REQUIRE(files.read({f.sha256, 0, 16, {}}).has_value());
  }
}
