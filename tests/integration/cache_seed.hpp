// Under the sanitizers, node caches that start warm: the packages an earlier test's nodes fetched
// are laid into a new node's cache before it starts (hard links, else copies), and a test's new
// packages are kept for the next. Why: an ASan component executable is ~66 MB, and fetching the
// two of an application over DDS took 4.4 s of a 9 s test (ProducerConsumer, measured), most of
// the sanitizer half of CI. The nodes' own code then does what it does after a restart with a
// warm cache: it checks each package is complete at start and hashes each file again at its
// first use (PackageCache::acquire), so a seed that is not what its manifest says is refused,
// not run. The optimised build keeps cold caches in every test, and the tests of delivery itself
// keep them under the sanitizers too (DefaultDelivery).
//
// The pool, shared by the tests of one build folder (two may run at once):
//   <build>/test-cache-seed/packages/<id>/   a package's files, as a node's cache holds them
//   <build>/test-cache-seed/manifests/<id>.json   written last: a package without one is not taken
#pragma once
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <set>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace rsca::test::cache_seed {

namespace fs = std::filesystem;

inline constexpr unsigned long long kLarge = 64 * 1024;

inline fs::path pool(const fs::path &bin) {
  return bin.parent_path() / "test-cache-seed";
}

// A tree linked (or copied, across file systems) into `to`, its folders' modes as in `from`:
// a package's folders are read-only, so they are made writable while filled and set after.
inline bool link_tree(const fs::path &from, const fs::path &to) {
  std::error_code ec;
  fs::create_directories(to, ec);
  if (ec)
    return false;
  for (const auto &entry : fs::directory_iterator(from, ec)) {
    const fs::path target = to / entry.path().filename();
    if (entry.is_directory()) {
      if (!link_tree(entry.path(), target))
        return false;
      continue;
    }
    fs::create_hard_link(entry.path(), target, ec);
    if (!ec)
      continue;
    // A copy keeps the modification time: a runtime model stamps its sources with it.
    if (!fs::copy_file(entry.path(), target, ec))
      return false;
    fs::last_write_time(target, fs::last_write_time(entry.path(), ec), ec);
  }
  fs::permissions(to, fs::status(from).permissions(), ec);
  return !ec;
}

inline void remove_tree(const fs::path &folder) {
  std::error_code ec;
  for (const auto &entry : fs::recursive_directory_iterator(folder, ec))
    if (entry.is_directory())
      fs::permissions(entry.path(), fs::perms::owner_all, fs::perm_options::add, ec);
  fs::permissions(folder, fs::perms::owner_all, fs::perm_options::add, ec);
  fs::remove_all(folder, ec);
}

// The name a DCD gives its node (its cache folder's name): <deviceconfiguration ... name="N">.
inline std::string node_name(const fs::path &dcd) {
  std::ifstream in(dcd);
  const std::string text{std::istreambuf_iterator<char>(in), {}};
  static const std::regex name(R"(<deviceconfiguration\b[^>]*\bname\s*=\s*"([^"]+)\")");
  std::smatch m;
  return std::regex_search(text, m, name) ? m[1].str() : std::string{};
}

// Every package of the pool into `cache` (a node's cache folder, before the node starts).
inline void seed(const fs::path &bin, const fs::path &cache) {
  const fs::path from = pool(bin);
  std::error_code ec;
  for (const auto &manifest : fs::directory_iterator(from / "manifests", ec)) {
    const std::string id = manifest.path().stem().string();
    if (manifest.path().extension() != ".json" || fs::exists(cache / "packages" / id))
      continue;
    fs::create_directories(cache / "manifests", ec);
    if (!link_tree(from / "packages" / id, cache / "packages" / id)) {
      remove_tree(cache / "packages" / id);
      continue;
    }
    fs::copy_file(manifest.path(), cache / "manifests" / manifest.path().filename(), ec);
  }
}

// The content hashes of the large files a manifest (protocol::Package) lists: the executables
// and libraries. A package's profiles and runtime model (it names the package's origin) differ
// from test to test and are fetched in a few milliseconds.
inline std::set<std::string> file_hashes(const fs::path &manifest) {
  std::ifstream in(manifest);
  const auto json = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  std::set<std::string> hashes;
  if (json.is_object() && json.contains("files") && json["files"].is_array())
    for (const auto &file : json["files"])
      if (file.is_object() && file.value("size", 0ULL) >= kLarge && file.contains("sha256") &&
          file["sha256"].is_string())
        hashes.insert(file["sha256"].get<std::string>());
  return hashes;
}

// The packages of `cache` with a file the pool lacks, into it (a package's id names the
// repository it came from, new at every test: the same executables come back in packages of
// other ids, and a node links a file it has by its hash, whichever package holds it). Laid out
// aside, then renamed into place (a test running at once may add the same package; the first
// rename wins), its manifest last.
inline void keep(const fs::path &bin, const fs::path &cache) {
  const fs::path to = pool(bin);
  std::error_code ec;
  fs::create_directories(to / "packages", ec);
  fs::create_directories(to / "manifests", ec);
  std::set<std::string> pooled;
  for (const auto &manifest : fs::directory_iterator(to / "manifests", ec))
    pooled.merge(file_hashes(manifest.path()));
  for (const auto &manifest : fs::directory_iterator(cache / "manifests", ec)) {
    const std::string id = manifest.path().stem().string();
    const auto hashes = file_hashes(manifest.path());
    if (manifest.path().extension() != ".json" ||
        std::includes(pooled.begin(), pooled.end(), hashes.begin(), hashes.end()))
      continue;
    pooled.insert(hashes.begin(), hashes.end());
    const fs::path aside = to / fmt::format(".{}.{}.{}", id, ::getpid(), std::random_device{}());
    if (link_tree(cache / "packages" / id, aside))
      fs::rename(aside, to / "packages" / id, ec);
    remove_tree(aside);
    if (!fs::exists(to / "packages" / id))
      continue;
    const fs::path manifest_aside = fs::path(aside).concat(".json");
    fs::copy_file(manifest.path(), manifest_aside, ec);
    fs::rename(manifest_aside, to / "manifests" / (id + ".json"), ec);
  }
}

} // namespace rsca::test::cache_seed
