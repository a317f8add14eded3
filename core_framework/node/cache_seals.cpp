#include "node/cache_seals.hpp"

#include <sys/stat.h>

#include <fmt/format.h>

#include "content/sha256.hpp"

namespace rsca::node::detail {

namespace {

// Past this many files verified, the records start again: every file is hashed at its next use.
// A cache holds far fewer files; the bound is for the inodes of packages evicted long ago.
constexpr std::size_t kMaxSeals = 1U << 16U;

std::int64_t nanoseconds(const timespec &t) {
  return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

} // namespace

std::optional<InodeStamp> inode_stamp(const std::filesystem::path &file) {
  struct stat st {};
  if (::lstat(file.c_str(), &st) != 0 || !S_ISREG(st.st_mode))
    return std::nullopt;
  return InodeStamp{st.st_dev, st.st_ino, st.st_size, nanoseconds(st.st_mtim),
                    nanoseconds(st.st_ctim)};
}

void CacheSeals::record(const std::filesystem::path &file, const std::string &sha256) {
  const auto stamp = inode_stamp(file);
  if (!stamp)
    return;
  std::lock_guard lock(mutex_);
  if (seals_.size() >= kMaxSeals)
    seals_.clear();
  seals_[{stamp->device, stamp->inode}] = {*stamp, sha256};
}

protocol::CallResult<void> CacheSeals::verify(const std::filesystem::path &file,
                                              const std::string &sha256, const std::string &name) {
  const auto stamp = inode_stamp(file);
  if (!stamp)
    return protocol::call_error(
        protocol::Status::Failed,
        fmt::format("{}: the cached copy is gone or not a regular file", name));
  {
    std::lock_guard lock(mutex_);
    auto it = seals_.find({stamp->device, stamp->inode});
    if (it != seals_.end() && it->second.stamp == *stamp && it->second.sha256 == sha256)
      return {};
  }
  auto found = content::sha256_of_file(file);
  if (!found)
    return protocol::call_error(
        protocol::Status::Failed,
        fmt::format("{}: the cached copy cannot be read: {}", name, found.error().to_string()));
  if (*found != sha256)
    return protocol::call_error(protocol::Status::Failed,
                                fmt::format("{}: the cached copy changed since it was verified: "
                                            "its content hashes to {}, the package says {}",
                                            name, *found, sha256));
  // Recorded with the stamp taken before the hash: a change while hashing shows at the next use.
  std::lock_guard lock(mutex_);
  if (seals_.size() >= kMaxSeals)
    seals_.clear();
  seals_[{stamp->device, stamp->inode}] = {*stamp, sha256};
  return {};
}

} // namespace rsca::node::detail
