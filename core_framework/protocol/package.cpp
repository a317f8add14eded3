#include "protocol/package.hpp"

#include <algorithm>
#include <set>
#include <string_view>

#include <fmt/format.h>

namespace rsca::protocol {

bool is_sha256_hex(std::string_view text) {
  return text.size() == 64 && std::all_of(text.begin(), text.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

std::optional<std::string> package_path_problem(const std::string &path) {
  if (path.empty())
    return "an empty path";
  if (path.size() > kMaxPackagePath)
    return fmt::format("a path of {} characters (at most {})", path.size(), kMaxPackagePath);
  if (path.find('\0') != std::string::npos)
    return "a path with a NUL character";
  if (path.front() == '/')
    return fmt::format("an absolute path \"{}\"", path);
  std::size_t begin = 0;
  while (begin <= path.size()) {
    const std::size_t end = std::min(path.find('/', begin), path.size());
    const std::string_view part(path.data() + begin, end - begin);
    if (part.empty() || part == "." || part == "..")
      return fmt::format("\"{}\": every part of a path names a file or folder", path);
    begin = end + 1;
  }
  return std::nullopt;
}

namespace {

// The library folders: few, sorted, each a folder some file of the package lies in.
std::optional<std::string> library_dirs_problem(const Package &package) {
  const auto &dirs = package.library_dirs;
  if (dirs.size() > kMaxLibraryDirs)
    return fmt::format("{} library folders (at most {})", dirs.size(), kMaxLibraryDirs);
  for (std::size_t i = 0; i < dirs.size(); ++i) {
    if (auto why = package_path_problem(dirs[i]))
      return fmt::format("library folder {}: {}", i, *why);
    if (i > 0 && !(dirs[i - 1] < dirs[i]))
      return fmt::format("library folder {}: not sorted, or there twice", dirs[i]);
    const std::string prefix = dirs[i] + "/";
    const auto in_it = [&](const PackageFile &f) { return f.path.starts_with(prefix); };
    if (std::none_of(package.files.begin(), package.files.end(), in_it))
      return fmt::format("library folder {}: no file of the package is in it", dirs[i]);
  }
  return std::nullopt;
}

} // namespace

std::optional<std::string> package_problem(const Package &package) {
  if (package.files.empty())
    return "a package without files";
  if (package.files.size() > kMaxPackageFiles)
    return fmt::format("{} files (at most {})", package.files.size(), kMaxPackageFiles);
  std::uint64_t bytes = 0;
  for (std::size_t i = 0; i < package.files.size(); ++i) {
    const auto &f = package.files[i];
    if (auto why = package_path_problem(f.path))
      return fmt::format("file {}: {}", i, *why);
    if (!is_sha256_hex(f.sha256))
      return fmt::format("{}: \"{}\" is not a SHA-256 in lowercase hex", f.path, f.sha256);
    if (i > 0 && !(package.files[i - 1].path < f.path))
      return fmt::format("{}: paths are not sorted, or one is there twice", f.path);
    if (f.size > kMaxPackageBytes - bytes)
      return fmt::format("more than {} bytes", kMaxPackageBytes);
    bytes += f.size;
  }
  // A file that is also a folder of another ("a" and "a/b") cannot be laid out; in sorted order
  // they need not be neighbours ("a", "a-x", "a/b").
  std::set<std::string_view> paths;
  for (const auto &f : package.files)
    paths.insert(f.path);
  for (const auto &f : package.files)
    for (auto slash = f.path.find('/'); slash != std::string::npos;
         slash = f.path.find('/', slash + 1))
      if (paths.count(std::string_view(f.path).substr(0, slash)) != 0)
        return fmt::format("{} is a file and a folder", f.path.substr(0, slash));
  return library_dirs_problem(package);
}

void sort_files(Package &package) {
  std::sort(package.files.begin(), package.files.end(),
            [](const PackageFile &a, const PackageFile &b) { return a.path < b.path; });
}

} // namespace rsca::protocol
