// FileManager: the domain's files, as its nodes get them. For each component process a launch
// starts it makes the package (protocol/package.hpp) of the files the process needs, found in the
// domain's repository (profiles, runtime models) and, for code an SPD names that an install did
// not carry, in the domain's exec path (where rsca's packages and a development build keep
// component executables and libraries); and it serves file.read of exactly those files, by
// content hash, to the nodes that fetch what their cache lacks (node/package_cache.hpp).
//
// Hashes are kept by file stamp (profile/file_stamp.hpp), so a launch hashes only files that
// changed. A file that changes after it was put into a package is not served under the old hash:
// the read fails, and the node's launch with it.
#pragma once

#include <cstdint>
#include <deque>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "domain/delivered_code.hpp"
#include "profile/file_stamp.hpp"
#include "profile/profile_loader.hpp"
#include "protocol/file_ops.hpp"
#include "protocol/package.hpp"
#include "protocol/status.hpp"

namespace rsca::domain {

using protocol::CallResult;

// One component a process runs: its package and the implementation placed.
struct PackagedComponent {
  std::string name; // the instance's id: errors name it
  const profile::ResolvedSoftPkg *softpkg = nullptr;
  const profile::Implementation *implementation = nullptr; // one of the softpkg's
};

class FileManager {
public:
  FileManager(std::filesystem::path repository, std::vector<std::filesystem::path> exec_path,
              CodeDelivery delivery = CodeDelivery::Stripped);

  // The package of a process that runs `components` (one, or a component host's several). An
  // error (Failed: the launch fails at execute) names the component and the file.
  CallResult<protocol::Package> package_of(const std::vector<PackagedComponent> &components);
  // Where the package puts `file` (a path in the repository): relative to the package's root.
  std::string package_path(const std::filesystem::path &file) const;

  CallResult<protocol::file::ReadReply> read(const protocol::file::ReadRequest &request);
  // Bytes served so far for `launch` (file.read's launch field): of the files, and on the wire.
  protocol::file::Delivered delivered(const std::string &launch) const;

private:
  struct Hashed {
    profile::FileStamp stamp;
    std::string sha256;              // of what is delivered
    std::filesystem::path delivered; // the file, or its copy without debug information
    std::uint64_t last_use = 0;
  };
  struct Served {
    std::filesystem::path file;
    profile::FileStamp stamp; // as it was hashed
    std::uint64_t last_use = 0;
  };
  // What a package is made of, as it is gathered.
  struct Contents {
    std::map<std::string, protocol::PackageFile> files; // by path: a file shared is there once
    std::set<std::string> library_dirs;
  };
  CallResult<void> add_softpkg(const profile::ResolvedSoftPkg &softpkg,
                               const profile::ResolvedImplementation &implementation, int depth,
                               Contents &contents);
  CallResult<void> add_code(const profile::ResolvedSoftPkg &softpkg,
                            const profile::ResolvedImplementation &implementation,
                            std::map<std::string, protocol::PackageFile> &files);
  std::optional<std::string>
  library_dir(const profile::ResolvedSoftPkg &softpkg,
              const profile::ResolvedImplementation &implementation,
              const std::map<std::string, protocol::PackageFile> &files) const;
  CallResult<void> add_file(const std::filesystem::path &file, const std::string &path,
                            std::map<std::string, protocol::PackageFile> &files);
  std::optional<std::filesystem::path> find_code(const std::filesystem::path &spd_dir,
                                                 const std::string &name) const;
  CallResult<protocol::PackageFile> describe(const std::filesystem::path &file,
                                             const std::string &path);
  void count(const std::optional<std::string> &launch, protocol::file::Delivered bytes);

  std::filesystem::path repository_;
  std::vector<std::filesystem::path> exec_path_;
  CodeDelivery delivery_;
  DeliveredCode code_;
  mutable std::mutex mutex_; // guards what follows
  // Both bounded: past 4096 entries, the least recently used goes.
  std::map<std::filesystem::path, Hashed> hashes_; // by file
  std::map<std::string, Served> served_;           // by hash: the file put into a package
  std::uint64_t uses_ = 0;
  std::map<std::string, protocol::file::Delivered> delivered_; // by launch
  std::deque<std::string> launches_;                           // of delivered_, oldest first
};

} // namespace rsca::domain
