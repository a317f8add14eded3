// A component's package: the files a node needs to run a component process (its executable or
// library, its softpkg dependencies' code, its SPD, PRFs and SCD, its runtime model), each named
// by its path inside the package and its content hash. The domain builds it (domain/
// file_manager.hpp) and sends it with node.execute; the node fetches what its cache lacks over
// file.read (protocol/file_ops.hpp), verifies it and runs the process inside it (node/
// package_cache.hpp). Checked here, once, for both parties: a node takes nothing from the network
// on trust.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "protocol/codec.hpp"

namespace rsca::protocol {

struct PackageFile {
  std::string path;   // relative, normal, inside the package: "components/Producer/rsca-producer"
  std::string sha256; // lowercase hex of its content
  std::uint64_t size = 0;
  bool executable = false;
  static constexpr auto fields() {
    using F = PackageFile;
    return std::tuple{required("path", &F::path), required("sha256", &F::sha256),
                      required("size", &F::size), optional("executable", &F::executable)};
  }
  bool operator==(const PackageFile &) const = default;
};

struct Package {
  // Where the domain's copies are (its repository): the runtime models it sent name their
  // sources there, and the node rewrites them to the package's paths.
  std::string origin;
  std::vector<PackageFile> files; // sorted by path, no path twice
  // Folders of the package that hold shared libraries its code needs (the code of its softpkg
  // dependencies of type SharedLibrary): the node puts them on the process's LD_LIBRARY_PATH, as
  // REDHAWK's GPP does. Sorted, each a folder of some file.
  std::vector<std::string> library_dirs;
  static constexpr auto fields() {
    return std::tuple{required("origin", &Package::origin), required("files", &Package::files),
                      optional("library_dirs", &Package::library_dirs)};
  }
  bool operator==(const Package &) const = default;
};

// Bounds a node holds a package to: a request from the network is untrusted.
inline constexpr std::size_t kMaxPackageFiles = 4096;
inline constexpr std::uint64_t kMaxPackageBytes = 16ULL << 30U; // 16 GiB
inline constexpr std::size_t kMaxPackagePath = 1024;
inline constexpr std::size_t kMaxLibraryDirs = 64;

// Whether `text` has the form of a SHA-256 in lowercase hex (the hash is computed in content/).
bool is_sha256_hex(std::string_view text);

// Why `path` may not name a file in a package (absolute, empty, "..", ".", "//", too long, a NUL);
// none when it may.
std::optional<std::string> package_path_problem(const std::string &path);
// Why `package` is not one to fetch (a bad path or hash, a path twice or out of order, too many
// files or bytes, a library folder that is not one of its folders); none when it is.
std::optional<std::string> package_problem(const Package &package);
// Puts the files in the order package_problem() asks for.
void sort_files(Package &package);

} // namespace rsca::protocol
