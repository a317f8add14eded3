// The node's package cache: where the packages of the processes it runs live (protocol/
// package.hpp). A process always runs inside its package in the cache; a package the cache lacks
// is fetched from the domain's FileManager (file.read) piece by piece, each file verified against
// its content hash, and the whole made visible at once (a folder renamed into place), so the cache
// never holds a file half written or unverified. A file the cache already has (the same hash in
// another package) is linked, not fetched again. Packages are evicted, least recently used
// first, when the cache holds more than its size; never one a running process is inside.
//
// On disk, under the cache's folder:
//   packages/<id>/...     a package's files, read-only (id: the SHA-256 of its manifest)
//   manifests/<id>.json   its manifest, written once the package is in place: a package without
//                         one is left from a node that stopped between the two, and removed
//   incoming/<id>.<pid>.<n>/  a package being fetched by node <pid>; removed on failure, and at
//                         start when that node is gone
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <future>
#include <memory>
#include <string>

#include "common/diagnostic.hpp"
#include "protocol/file_ops.hpp"
#include "protocol/package.hpp"
#include "protocol/status.hpp"

namespace rsca::node {

using protocol::CallResult;

// Asks the domain for a piece of a file: the node's endpoint calling file.read.
using FetchPiece = std::function<std::future<CallResult<nlohmann::json>>(
    const protocol::file::ReadRequest &request)>;

struct CacheOptions {
  std::filesystem::path dir;
  std::uint64_t max_bytes = 1ULL << 30U; // packages beyond it are evicted, oldest use first
  unsigned pieces_in_flight = 4;         // file.read calls under way at once, per file
  std::chrono::milliseconds piece_timeout{10000};
};

struct CacheCounts {
  std::uint64_t packages = 0;
  std::uint64_t bytes = 0;         // of their files (a file linked into two counts twice)
  std::uint64_t fetched_bytes = 0; // since the node started
  std::uint64_t reused = 0;        // launches that found their package here
  std::uint64_t fetched = 0;       // packages fetched
};

// A package in use: its folder stays until the last lease of it is gone.
class PackageLease {
public:
  virtual ~PackageLease() = default;
  virtual const std::filesystem::path &root() const = 0;
};

class PackageCache {
public:
  static Expected<std::unique_ptr<PackageCache>> open(CacheOptions options, FetchPiece fetch);
  ~PackageCache();
  PackageCache(const PackageCache &) = delete;
  PackageCache &operator=(const PackageCache &) = delete;

  // The package in the cache, fetched first when it is not there. Concurrent calls for one
  // package fetch it once. An error says which file and why (verification, a transfer cut off,
  // a full disk), and leaves nothing of the package behind.
  CallResult<std::shared_ptr<const PackageLease>> acquire(const protocol::Package &package,
                                                          const std::string &launch);
  CacheCounts counts() const;

  struct State;

private:
  explicit PackageCache(std::shared_ptr<State> state);
  std::shared_ptr<State> state_; // shared with the leases, which may outlive the cache
};

// The id of a package: the SHA-256 of its manifest as JSON.
std::string package_id(const protocol::Package &package);

} // namespace rsca::node
