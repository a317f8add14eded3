// What the domain and a node agree a package is (protocol/package.hpp), and the content hashes
// that name its files (content/): a node takes no path or hash from the network on trust.
#include "content/sha256.hpp"
#include "protocol/package.hpp"

#include <catch2/catch.hpp>

#include <fstream>

#include "temp_dir.hpp"

using namespace rsca;
using Catch::Matchers::Contains;

namespace {

const std::string kHashA(64, 'a');
const std::string kHashB(64, 'b');

protocol::Package two_files() {
  return {"/srv/repository",
          {{"applications/A/c/C.spd.xml", kHashA, 10, false},
           {"applications/A/c/run", kHashB, 20, true}},
          {}};
}

} // namespace

TEST_CASE("content: SHA-256 of bytes and of a file is the standard one", "[package]") {
  // FIPS 180-2's example "abc".
  CHECK(content::sha256_hex("abc") ==
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  test::TempDir dir;
  {
    std::ofstream out(dir.path() / "f");
    out << "abc";
  }
  CHECK(content::sha256_of_file(dir.path() / "f").value() == content::sha256_hex("abc"));
  CHECK_FALSE(content::sha256_of_file(dir.path() / "missing").has_value());
  CHECK(protocol::is_sha256_hex(kHashA));
  CHECK_FALSE(protocol::is_sha256_hex(std::string(64, 'A')));
  CHECK_FALSE(protocol::is_sha256_hex("abc"));
}

TEST_CASE("package: a well-formed package passes, sorted by path", "[package]") {
  auto package = two_files();
  std::swap(package.files[0], package.files[1]);
  CHECK(protocol::package_problem(package).has_value()); // out of order
  protocol::sort_files(package);
  CHECK_FALSE(protocol::package_problem(package).has_value());
}

TEST_CASE("package: a path that could leave the package, a bad hash or a repeated path is refused",
          "[package]") {
  for (const std::string path : {"/etc/passwd", "../x", "a/../../x", "a//b", "./a", "a/.", ""}) {
    auto package = two_files();
    package.files[0].path = path;
    protocol::sort_files(package);
    INFO(path);
    CHECK(protocol::package_problem(package).has_value());
  }
  auto bad_hash = two_files();
  bad_hash.files[1].sha256 = "not a hash";
  CHECK_THAT(protocol::package_problem(bad_hash).value(), Contains("SHA-256"));
  auto twice = two_files();
  twice.files[1].path = twice.files[0].path;
  CHECK_THAT(protocol::package_problem(twice).value(), Contains("twice"));
  auto file_and_folder = two_files();
  file_and_folder.files[1].path = file_and_folder.files[0].path + "/x";
  CHECK_THAT(protocol::package_problem(file_and_folder).value(), Contains("a file and a folder"));
  // Not neighbours once sorted: '-' sorts before '/'.
  protocol::Package apart{
      "/r", {{"a", kHashA, 1, false}, {"a-x", kHashA, 1, false}, {"a/b", kHashB, 1, false}}, {}};
  CHECK_THAT(protocol::package_problem(apart).value(), Contains("a file and a folder"));
  auto too_big = two_files();
  too_big.files[1].size = protocol::kMaxPackageBytes;
  CHECK(protocol::package_problem(too_big).has_value());
  CHECK(protocol::package_problem({"/r", {}, {}}).has_value());
}

TEST_CASE("package: library folders must be its own folders, sorted, and few", "[package]") {
  auto package = two_files();
  package.library_dirs = {"applications/A", "applications/A/c"};
  CHECK_FALSE(protocol::package_problem(package).has_value());
  const std::vector<std::pair<std::vector<std::string>, const char *>> refused = {
      {{"/usr/lib"}, "an absolute path"},
      {{"applications/../etc"}, "every part of a path"},
      {{"applications/B"}, "no file of the package is in it"},
      {{"applications/A/c/run"}, "no file of the package is in it"}, // a file, not a folder
      {{"applications/A/c", "applications/A"}, "not sorted"},
      {{"applications/A", "applications/A"}, "there twice"},
  };
  for (const auto &[dirs, why] : refused) {
    package.library_dirs = dirs;
    const auto problem = protocol::package_problem(package);
    INFO(dirs.front());
    REQUIRE(problem.has_value());
    CHECK_THAT(*problem, Contains(why));
  }
  package.library_dirs.assign(protocol::kMaxLibraryDirs + 1, "applications/A");
  CHECK_THAT(protocol::package_problem(package).value_or(""), Contains("library folders"));
}
