#include "domain/file_manager.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>

#include "common/names.hpp"
#include "content/sha256.hpp"
#include "content/zstd.hpp"
#include "process/fd.hpp"
#include "profile/runtime_model.hpp"

namespace rsca::domain {

namespace fs = std::filesystem;
using protocol::Status;

namespace {

constexpr std::size_t kMaxKept = 4096;    // files hashed and served that are remembered
constexpr std::size_t kLaunchesKept = 64; // launches whose delivered bytes are remembered

CallResult<void> fail(Status status, std::string message) {
  return protocol::call_error(status, std::move(message));
}

// Drops the least recently used entry of `map` once it holds more than kMaxKept; returns it.
template <typename Map>
std::optional<typename Map::mapped_type> bound(Map &map) {
  if (map.size() <= kMaxKept)
    return std::nullopt;
  auto oldest = map.begin();
  for (auto it = map.begin(); it != map.end(); ++it)
    if (it->second.last_use < oldest->second.last_use)
      oldest = it;
  auto dropped = std::move(oldest->second);
  map.erase(oldest);
  return dropped;
}

bool is_executable_file(const fs::path &file) {
  struct stat st {};
  return ::stat(file.c_str(), &st) == 0 && (st.st_mode & S_IXUSR) != 0;
}

} // namespace

FileManager::FileManager(fs::path repository, std::vector<fs::path> exec_path,
                         CodeDelivery delivery)
    : repository_(fs::weakly_canonical(repository)), exec_path_(std::move(exec_path)),
      delivery_(delivery), code_(repository_) {}

std::string FileManager::package_path(const fs::path &file) const {
  const fs::path relative = file.lexically_normal().lexically_relative(repository_);
  if (relative.empty() || *relative.begin() == "..")
    return {};
  return relative.generic_string();
}

CallResult<protocol::Package>
FileManager::package_of(const std::vector<PackagedComponent> &components) {
  Contents contents;
  for (const auto &c : components) {
    const auto &implementations = c.softpkg->implementations;
    auto placed = std::find_if(implementations.begin(), implementations.end(),
                               [&](const auto &i) { return i.implementation == c.implementation; });
    if (placed == implementations.end())
      return protocol::call_error(Status::Failed, fmt::format("{}: the implementation placed is "
                                                              "not its SPD's",
                                                              c.name));
    if (auto ok = add_softpkg(*c.softpkg, *placed, 0, contents); !ok)
      return protocol::call_error(Status::Failed,
                                  fmt::format("{}: {}", c.name, ok.error().message));
  }
  protocol::Package package{repository_.string(), {}, {}};
  for (auto &[path, file] : contents.files)
    package.files.push_back(std::move(file));
  package.library_dirs.assign(contents.library_dirs.begin(), contents.library_dirs.end());
  if (auto why = protocol::package_problem(package))
    return protocol::call_error(Status::Failed, fmt::format("its package: {}", *why));
  return package;
}

// Its profile files and runtime model, the implementation's code, and its softpkg dependencies'
// code with their profiles.
CallResult<void> FileManager::add_softpkg(const profile::ResolvedSoftPkg &softpkg,
                                          const profile::ResolvedImplementation &implementation,
                                          int depth, Contents &contents) {
  auto &files = contents.files;
  if (depth > profile::kMaxSoftpkgDependencyDepth)
    return fail(Status::BadRequest, "softpkg dependencies nest too deep");
  for (const auto &source : softpkg.sources)
    if (auto ok = add_file(source.path, package_path(source.path), files); !ok)
      return ok;
  const fs::path model = profile::runtime_model_path(softpkg.spd_path);
  if (std::error_code ec; fs::exists(model, ec))
    if (auto ok = add_file(model, package_path(model), files); !ok)
      return ok;
  if (auto ok = add_code(softpkg, implementation, files); !ok)
    return ok;
  if (depth > 0)
    if (auto dir = library_dir(softpkg, implementation, files))
      contents.library_dirs.insert(std::move(*dir));
  for (const auto &dependency : implementation.dependencies) {
    const auto &pkg = *dependency.softpkg;
    for (const auto &candidate : pkg.implementations) {
      if (dependency.implref && candidate.implementation->id != *dependency.implref)
        continue;
      if (auto ok = add_softpkg(pkg, candidate, depth + 1, contents); !ok)
        return ok;
    }
  }
  return {};
}

// Where a dependency's shared library code is in the package, for LD_LIBRARY_PATH: the folder of
// its code file, or its code folder. None for other code, and for code installed on the node
// itself (an absolute name: the node's own library path finds it).
std::optional<std::string>
FileManager::library_dir(const profile::ResolvedSoftPkg &softpkg,
                         const profile::ResolvedImplementation &implementation,
                         const std::map<std::string, protocol::PackageFile> &files) const {
  const auto &code = implementation.implementation->code;
  if (code.type != profile::CodeType::SharedLibrary || code.file.name.empty() ||
      fs::path(code.file.name).is_absolute())
    return std::nullopt;
  const std::string path = package_path(softpkg.spd_path.parent_path() / code.file.name);
  if (path.empty())
    return std::nullopt;
  if (files.count(path) == 0)
    return path; // a folder of files
  const std::string folder = fs::path(path).parent_path().generic_string();
  return folder.empty() ? std::nullopt : std::optional<std::string>(folder);
}

// The code file (or folder) the implementation names, at its place beside the SPD in the package
// wherever the domain found it.
CallResult<void> FileManager::add_code(const profile::ResolvedSoftPkg &softpkg,
                                       const profile::ResolvedImplementation &implementation,
                                       std::map<std::string, protocol::PackageFile> &files) {
  const auto &code = implementation.implementation->code;
  if (code.file.name.empty())
    return {};
  // REDHAWK allows code installed on the node itself; a node runs only code of its package
  // (gpp/gpp_device.cpp), the control plane not being authenticated: refused here, before any
  // node is asked.
  if (fs::path(code.file.name).is_absolute())
    return fail(Status::BadRequest,
                fmt::format("{}: code file {} is an absolute path: a node runs only code the "
                            "domain delivers; put it beside the SPD or in the domain's exec path",
                            softpkg.spd_path.string(), code.file.name));
  const fs::path spd_dir = softpkg.spd_path.parent_path();
  const std::string path = package_path(spd_dir / code.file.name);
  if (path.empty())
    return fail(Status::BadRequest,
                fmt::format("{}: code file {} lies outside the application's folder",
                            softpkg.spd_path.string(), code.file.name));
  auto found = find_code(spd_dir, code.file.name);
  if (!found)
    return fail(Status::NotFound,
                fmt::format("{}: code file {} is neither beside the SPD nor in the domain's exec "
                            "path",
                            softpkg.spd_path.string(), code.file.name));
  std::error_code ec;
  if (!fs::is_directory(*found, ec))
    return add_file(*found, path, files);
  for (auto it = fs::recursive_directory_iterator(*found, ec); !ec && it != fs::end(it);
       it.increment(ec)) {
    if (!it->is_regular_file(ec))
      continue;
    if (files.size() > protocol::kMaxPackageFiles)
      return fail(Status::BadRequest, fmt::format("{}: too many files", found->string()));
    const std::string inside = it->path().lexically_relative(*found).generic_string();
    if (auto ok = add_file(it->path(), path + "/" + inside, files); !ok)
      return ok;
  }
  if (ec)
    return fail(Status::Failed, fmt::format("{}: {}", found->string(), ec.message()));
  return {};
}

// Beside the SPD, where an install that carries code puts it; else by its file name in the exec
// path, executables in a folder of it and libraries also in the lib folder beside it.
std::optional<fs::path> FileManager::find_code(const fs::path &spd_dir,
                                               const std::string &name) const {
  std::error_code ec;
  if (fs::exists(spd_dir / name, ec))
    return spd_dir / name;
  const fs::path file = fs::path(name).filename();
  for (const auto &dir : exec_path_)
    for (const auto &candidate : {dir / file, dir / ".." / "lib" / file})
      if (fs::exists(candidate, ec))
        return candidate.lexically_normal();
  return std::nullopt;
}

CallResult<void> FileManager::add_file(const fs::path &file, const std::string &path,
                                       std::map<std::string, protocol::PackageFile> &files) {
  if (path.empty())
    return fail(Status::BadRequest, fmt::format("{} lies outside the domain's repository {}",
                                                file.string(), repository_.string()));
  if (files.count(path) != 0)
    return {};
  auto described = describe(file, path);
  if (!described)
    return tl::unexpected(described.error());
  files.emplace(path, std::move(*described));
  return {};
}

// What is delivered of the file (itself, or its copy without debug information) and its hash,
// both made again only when the file's stamp changed, and its name in the package. It is served
// from now on.
CallResult<protocol::PackageFile> FileManager::describe(const fs::path &file,
                                                        const std::string &path) {
  const auto stamp = profile::stamp_of(file);
  if (!stamp)
    return protocol::call_error(Status::NotFound, fmt::format("{} cannot be read", file.string()));
  std::string sha256;
  fs::path delivered;
  {
    std::lock_guard lock(mutex_);
    if (auto it = hashes_.find(file); it != hashes_.end() && it->second.stamp == *stamp) {
      sha256 = it->second.sha256;
      delivered = it->second.delivered;
    }
  }
  auto delivered_stamp = profile::stamp_of(delivered); // none: a copy forgotten since
  if (sha256.empty() || !delivered_stamp) {
    delivered = delivery_ == CodeDelivery::Stripped ? code_.deliverable(file) : file;
    auto hashed = content::sha256_of_file(delivered);
    delivered_stamp = profile::stamp_of(delivered);
    if (!hashed || !delivered_stamp)
      return protocol::call_error(Status::Failed,
                                  hashed ? fmt::format("{} cannot be read", delivered.string())
                                         : hashed.error().to_string());
    sha256 = std::move(*hashed);
  }
  std::optional<Served> forgotten;
  {
    std::lock_guard lock(mutex_);
    hashes_[file] = {*stamp, sha256, delivered, ++uses_};
    served_[sha256] = {delivered, *delivered_stamp, uses_};
    bound(hashes_);
    forgotten = bound(served_);
  }
  if (forgotten)
    code_.forget(forgotten->file);
  return protocol::PackageFile{path, sha256, delivered_stamp->size, is_executable_file(file)};
}

CallResult<protocol::file::ReadReply>
FileManager::read(const protocol::file::ReadRequest &request) {
  if (!protocol::is_sha256_hex(request.sha256))
    return protocol::call_error(Status::BadRequest, "sha256: not a SHA-256 in lowercase hex");
  if (request.compression && *request.compression != protocol::file::kZstd)
    return protocol::call_error(Status::BadRequest,
                                fmt::format("compression: \"{}\" is not one the domain makes (it "
                                            "makes {})",
                                            excerpt(*request.compression), protocol::file::kZstd));
  if (request.length > protocol::file::kMaxReadBytes)
    return protocol::call_error(
        Status::BadRequest,
        fmt::format("length {} is over {}", request.length, protocol::file::kMaxReadBytes));
  fs::path file;
  std::optional<profile::FileStamp> hashed_as;
  {
    std::lock_guard lock(mutex_);
    auto it = served_.find(request.sha256);
    if (it == served_.end())
      return protocol::call_error(Status::NotFound,
                                  fmt::format("no file {} in a package", request.sha256));
    it->second.last_use = ++uses_;
    file = it->second.file;
    hashed_as = it->second.stamp;
  }
  if (!hashed_as || profile::stamp_of(file) != hashed_as)
    return protocol::call_error(Status::Failed,
                                fmt::format("{} changed since it was put into the package; launch "
                                            "again",
                                            file.string()));
  if (request.offset > hashed_as->size)
    return protocol::call_error(Status::BadRequest,
                                fmt::format("offset {} is past the end of {} ({} bytes)",
                                            request.offset, file.string(), hashed_as->size));
  process::Fd fd(::open(file.c_str(), O_RDONLY | O_CLOEXEC));
  if (!fd)
    return protocol::call_error(Status::Failed,
                                fmt::format("{}: {}", file.string(), std::strerror(errno)));
  const auto wanted = std::min<std::uint64_t>(request.length, hashed_as->size - request.offset);
  protocol::Bytes::container_type bytes(wanted);
  std::size_t got = 0;
  while (got < wanted) {
    const ssize_t n = ::pread(fd.get(), bytes.data() + got, wanted - got,
                              static_cast<off_t>(request.offset + got));
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0)
      break; // cut short: the node sees fewer bytes than it asked for, and the hash tells
    got += static_cast<std::size_t>(n);
  }
  bytes.resize(got);
  protocol::file::ReadReply reply{protocol::Bytes{}, hashed_as->size, std::nullopt};
  if (request.compression && delivery_ == CodeDelivery::Stripped && got > 0) {
    auto frame = content::zstd_compress(bytes.data(), bytes.size());
    if (!frame.empty() && frame.size() < bytes.size()) {
      bytes = std::move(frame);
      reply.compression = std::string(protocol::file::kZstd);
    }
  }
  count(request.launch, {got, bytes.size()});
  reply.payload = protocol::Bytes(std::move(bytes));
  return reply;
}

void FileManager::count(const std::optional<std::string> &launch, protocol::file::Delivered bytes) {
  if (!launch)
    return;
  std::lock_guard lock(mutex_);
  auto [it, fresh] = delivered_.try_emplace(*launch);
  it->second.bytes += bytes.bytes;
  it->second.wire_bytes += bytes.wire_bytes;
  if (!fresh)
    return;
  launches_.push_back(*launch);
  if (launches_.size() > kLaunchesKept) {
    delivered_.erase(launches_.front());
    launches_.pop_front();
  }
}

protocol::file::Delivered FileManager::delivered(const std::string &launch) const {
  std::lock_guard lock(mutex_);
  auto it = delivered_.find(launch);
  return it == delivered_.end() ? protocol::file::Delivered{} : it->second;
}

} // namespace rsca::domain
