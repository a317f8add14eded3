#include "node/package_cache.hpp"

#include <condition_variable>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>

#include <signal.h>
#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "content/sha256.hpp"
#include "node/cache_seals.hpp"
#include "node/package_fetch.hpp"
#include "profile/runtime_model.hpp"

namespace rsca::node {

namespace fs = std::filesystem;
using protocol::Status;

std::string package_id(const protocol::Package &package) {
  return content::sha256_hex(protocol::encode(package).dump());
}

namespace {

std::uint64_t bytes_of(const protocol::Package &package) {
  std::uint64_t bytes = 0;
  for (const auto &f : package.files)
    bytes += f.size;
  return bytes;
}

// "<id>.<pid>.<n>" of a folder in incoming/: the pid of the node that made it.
std::optional<pid_t> maker_of(const std::string &name) {
  const auto first = name.find('.');
  const auto second = name.find('.', first + 1);
  if (first == std::string::npos || second == std::string::npos)
    return std::nullopt;
  try {
    return static_cast<pid_t>(std::stol(name.substr(first + 1, second - first - 1)));
  } catch (const std::exception &) {
    return std::nullopt;
  }
}

bool alive(pid_t pid) {
  return pid > 0 && (::kill(pid, 0) == 0 || errno == EPERM);
}

// A package's folders are read-only (package_fetch.cpp): writable again first,
// as removing what they hold needs.
void remove_folder(const fs::path &folder) {
  std::error_code ec;
  if (!fs::exists(folder, ec))
    return;
  fs::permissions(folder, fs::perms::owner_all, fs::perm_options::add, ec);
  for (auto it = fs::recursive_directory_iterator(folder, ec); !ec && it != fs::end(it);
       it.increment(ec))
    if (it->is_directory(ec) && !it->is_symlink(ec))
      fs::permissions(it->path(), fs::perms::owner_all, fs::perm_options::add, ec);
  ec.clear();
  fs::remove_all(folder, ec);
  if (ec)
    spdlog::warn("package cache: cannot remove {}: {}", folder.string(), ec.message());
}

// Whether the files the manifest lists are there, with their sizes: a package a
// node crashed while writing, or that someone changed, is not trusted.
bool complete(const fs::path &root, const protocol::Package &manifest) {
  std::error_code ec;
  for (const auto &f : manifest.files)
    if (profile::is_runtime_model_path(f.path) ? !fs::exists(root / f.path, ec)
                                               : fs::file_size(root / f.path, ec) != f.size || ec)
      return false;
  return true;
}

// The runtime models as the node rewrote them (relocate_runtime_model): not the
// package's hashes, so their own, taken when they are written or found at
// start.
std::map<std::string, std::string> model_hashes(const fs::path &root,
                                                const protocol::Package &manifest) {
  std::map<std::string, std::string> hashes;
  for (const auto &f : manifest.files)
    if (profile::is_runtime_model_path(f.path))
      hashes[f.path] = content::sha256_of_file(root / f.path).value_or("");
  return hashes;
}

} // namespace

struct PackageCache::State {
  struct Entry {
    protocol::Package manifest;
    std::map<std::string, std::string> models; // path → the hash of the model as rewritten
    std::uint64_t bytes = 0;
    std::uint64_t last_use = 0; // a counter: larger is more recent
    unsigned leases = 0;
  };

  CacheOptions options;
  FetchPiece fetch;
  mutable std::mutex mutex; // guards what follows
  std::condition_variable fetched_cv;
  std::map<std::string, Entry> packages;     // by id
  std::map<std::string, bool> fetching;      // ids being fetched
  std::map<std::string, std::string> copies; // file hash → a package holding it, by id
  detail::CacheSeals seals;                  // its own lock
  std::uint64_t uses = 0;
  std::uint64_t incoming = 0;
  CacheCounts counts;

  fs::path packages_dir() const { return options.dir / "packages"; }
  fs::path manifests_dir() const { return options.dir / "manifests"; }
  fs::path incoming_dir() const { return options.dir / "incoming"; }
  fs::path root_of(const std::string &id) const { return packages_dir() / id; }

  void load();
  void add_locked(const std::string &id, protocol::Package manifest,
                  std::map<std::string, std::string> models);
  void evict_locked();
  void drop_locked(const std::string &id);
  void seal(const std::string &id, const protocol::Package &package,
            const std::map<std::string, std::string> &models);
  CallResult<void> verify(const std::string &id, const protocol::Package &package,
                          const std::map<std::string, std::string> &models);
  std::optional<fs::path> copy_of(const protocol::PackageFile &file) const;
  std::optional<fs::path> verified_copy(const protocol::PackageFile &file);
  CallResult<void> fetch_into_place(const std::string &id, const protocol::Package &package,
                                    const std::string &launch);
  CallResult<void> write_manifest(const std::string &id, const protocol::Package &package) const;
};

class CachedPackage final : public PackageLease {
public:
  CachedPackage(std::shared_ptr<PackageCache::State> state, std::string id)
      : state_(std::move(state)), id_(std::move(id)), root_(state_->root_of(id_)) {}
  // Only counts: a package kept over the cache's size goes at the next acquire,
  // not here on the thread that saw its process exit (the GPP's reaper, which
  // must not block).
  ~CachedPackage() override {
    std::lock_guard lock(state_->mutex);
    if (auto it = state_->packages.find(id_); it != state_->packages.end() && it->second.leases > 0)
      --it->second.leases;
  }
  const fs::path &root() const override { return root_; }

private:
  std::shared_ptr<PackageCache::State> state_;
  std::string id_;
  fs::path root_;
};

// What a node left: folders it was fetching into (when it is gone), packages
// without their manifest (it stopped before writing it) and manifests without
// their package.
void PackageCache::State::load() {
  std::error_code ec;
  for (const auto &entry : fs::directory_iterator(incoming_dir(), ec)) {
    // One of this pid is of an earlier node that had it (a container's node is
    // often pid 1).
    const auto maker = maker_of(entry.path().filename().string());
    if (!maker || !alive(*maker) || *maker == ::getpid())
      remove_folder(entry.path());
  }
  for (const auto &entry : fs::directory_iterator(packages_dir(), ec)) {
    const std::string id = entry.path().filename().string();
    std::ifstream in(manifests_dir() / (id + ".json"));
    const auto json = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
    auto manifest = protocol::decode<protocol::Package>(json);
    if (json.is_discarded() || !manifest || package_id(*manifest) != id ||
        !complete(entry.path(), *manifest)) {
      spdlog::info("package cache: {} has no manifest or lacks files; removed", id);
      remove_folder(entry.path());
      fs::remove(manifests_dir() / (id + ".json"), ec);
      continue;
    }
    auto models = model_hashes(entry.path(), *manifest);
    add_locked(id, std::move(*manifest), std::move(models));
  }
  for (const auto &entry : fs::directory_iterator(manifests_dir(), ec))
    if (!fs::exists(packages_dir() / entry.path().stem(), ec))
      fs::remove(entry.path(), ec);
}

void PackageCache::State::add_locked(const std::string &id, protocol::Package manifest,
                                     std::map<std::string, std::string> models) {
  for (const auto &f : manifest.files)
    if (!profile::is_runtime_model_path(f.path)) // rewritten here: not the hash's content
      copies[f.sha256] = id;
  Entry entry{std::move(manifest), std::move(models), 0, ++uses, 0};
  entry.bytes = bytes_of(entry.manifest);
  counts.bytes += entry.bytes;
  ++counts.packages;
  packages[id] = std::move(entry);
}

// Least recently used first, until the cache fits its size; a package in use
// stays.
void PackageCache::State::evict_locked() {
  while (counts.bytes > options.max_bytes) {
    auto victim = packages.end();
    for (auto it = packages.begin(); it != packages.end(); ++it)
      if (it->second.leases == 0 &&
          (victim == packages.end() || it->second.last_use < victim->second.last_use))
        victim = it;
    if (victim == packages.end())
      return; // everything left is in use
    spdlog::info("package cache: evicting {} ({} bytes) to stay under {} bytes", victim->first,
                 victim->second.bytes, options.max_bytes);
    drop_locked(victim->first);
  }
}

// Out of the cache. A package a process still runs inside is moved aside into
// incoming/ under this node's pid (its processes keep their folder), and
// removed when the node next starts.
void PackageCache::State::drop_locked(const std::string &id) {
  auto it = packages.find(id);
  if (it == packages.end())
    return;
  std::error_code ec;
  fs::remove(manifests_dir() / (id + ".json"), ec);
  if (it->second.leases == 0) {
    remove_folder(root_of(id));
  } else {
    fs::rename(root_of(id), incoming_dir() / fmt::format("{}.{}.{}", id, ::getpid(), ++incoming),
               ec);
    if (ec)
      remove_folder(root_of(id));
  }
  for (auto c = copies.begin(); c != copies.end();)
    c = c->second == id ? copies.erase(c) : std::next(c);
  counts.bytes -= it->second.bytes;
  --counts.packages;
  packages.erase(it);
}

// The files of a package just laid out are what was verified: their stamps are
// recorded.
void PackageCache::State::seal(const std::string &id, const protocol::Package &package,
                               const std::map<std::string, std::string> &models) {
  for (const auto &f : package.files) {
    const auto model = models.find(f.path);
    seals.record(root_of(id) / f.path, model == models.end() ? f.sha256 : model->second);
  }
}

// Each file of a cached package still is what was verified (its stat, or its
// hash when the stat changed): a process runs only what the package says.
CallResult<void> PackageCache::State::verify(const std::string &id,
                                             const protocol::Package &package,
                                             const std::map<std::string, std::string> &models) {
  for (const auto &f : package.files) {
    const auto model = models.find(f.path);
    const std::string &sha256 = model == models.end() ? f.sha256 : model->second;
    if (auto ok = seals.verify(root_of(id) / f.path, sha256, f.path); !ok)
      return ok;
  }
  return {};
}

std::optional<fs::path> PackageCache::State::copy_of(const protocol::PackageFile &file) const {
  std::lock_guard lock(mutex);
  auto it = copies.find(file.sha256);
  if (it == copies.end())
    return std::nullopt;
  auto package = packages.find(it->second);
  if (package == packages.end())
    return std::nullopt;
  std::optional<fs::path> copy;
  for (const auto &f : package->second.manifest.files)
    if (f.sha256 == file.sha256)
      copy = root_of(it->second) / f.path;
  return copy;
}

// A copy to link only while it still is what was verified; one that is not is
// fetched instead, and its own package is refused at its next use.
std::optional<fs::path> PackageCache::State::verified_copy(const protocol::PackageFile &file) {
  auto copy = copy_of(file);
  if (!copy)
    return std::nullopt;
  if (auto ok = seals.verify(*copy, file.sha256, copy->string()); !ok) {
    spdlog::warn("package cache: not linking {}: {}", file.path, ok.error().message);
    return std::nullopt;
  }
  return copy;
}

CallResult<void> PackageCache::State::write_manifest(const std::string &id,
                                                     const protocol::Package &package) const {
  const fs::path target = manifests_dir() / (id + ".json");
  const fs::path temporary = fs::path(target).concat(fmt::format(".{}.tmp", ::getpid()));
  std::ofstream out(temporary, std::ios::trunc);
  out << protocol::encode(package).dump();
  out.close();
  std::error_code ec;
  if (out)
    fs::rename(temporary, target, ec);
  if (!out || ec) {
    fs::remove(temporary, ec);
    return protocol::call_error(
        Status::Failed, fmt::format("cannot write {} (is the disk full?)", target.string()));
  }
  return {};
}

// Fetched into a folder of its own in incoming/, then renamed into place; on
// failure nothing of it is left.
CallResult<void> PackageCache::State::fetch_into_place(const std::string &id,
                                                       const protocol::Package &package,
                                                       const std::string &launch) {
  fs::path folder;
  {
    std::lock_guard lock(mutex);
    folder = incoming_dir() / fmt::format("{}.{}.{}", id, ::getpid(), ++incoming);
  }
  detail::FetchContext context{fetch, &options, launch,
                               [this](const protocol::PackageFile &f) { return verified_copy(f); }};
  auto fetched = detail::lay_out(context, package, folder);
  std::error_code ec;
  if (fetched) {
    fs::rename(folder, root_of(id), ec);
    if (ec && fs::exists(root_of(id))) { // left by an eviction that could not remove it all
      remove_folder(root_of(id));
      fs::rename(folder, root_of(id), ec);
    }
  }
  if (!fetched || ec) {
    remove_folder(folder);
    if (fetched)
      return protocol::call_error(Status::Failed, fmt::format("cannot move package {} into place: "
                                                              "{}",
                                                              id, ec.message()));
    return tl::unexpected(fetched.error());
  }
  if (auto ok = write_manifest(id, package); !ok) {
    remove_folder(root_of(id));
    return ok;
  }
  std::lock_guard lock(mutex);
  counts.fetched_bytes += *fetched;
  ++counts.fetched;
  spdlog::info("package {}: {} files in place, {} bytes fetched", id, package.files.size(),
               *fetched);
  return {};
}

PackageCache::PackageCache(std::shared_ptr<State> state) : state_(std::move(state)) {}
PackageCache::~PackageCache() = default;

Expected<std::unique_ptr<PackageCache>> PackageCache::open(CacheOptions options, FetchPiece fetch) {
  auto state = std::make_shared<State>();
  state->options = std::move(options);
  state->fetch = std::move(fetch);
  for (const auto &dir : {state->packages_dir(), state->manifests_dir(), state->incoming_dir()}) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec)
      return make_error({dir.string(), 0, 0}, "cache", ec.message());
  }
  {
    std::lock_guard lock(state->mutex);
    state->load();
    state->evict_locked();
  }
  spdlog::info("package cache {}: {} packages, {} bytes (at most {})", state->options.dir.string(),
               state->counts.packages, state->counts.bytes, state->options.max_bytes);
  return std::unique_ptr<PackageCache>(new PackageCache(std::move(state)));
}

CallResult<std::shared_ptr<const PackageLease>>
PackageCache::acquire(const protocol::Package &package, const std::string &launch) {
  if (auto why = protocol::package_problem(package))
    return protocol::call_error(Status::BadRequest, fmt::format("package: {}", *why));
  const std::string id = package_id(package);
  State &s = *state_;
  std::unique_lock lock(s.mutex);
  // Another call fetching it: wait for its outcome, then look again.
  s.fetched_cv.wait(lock, [&] { return s.fetching.count(id) == 0; });
  if (auto it = s.packages.find(id); it != s.packages.end()) {
    it->second.last_use = ++s.uses;
    ++it->second.leases;
    ++s.counts.reused;
    auto lease = std::make_shared<CachedPackage>(state_, id);
    const auto models = it->second.models;
    s.evict_locked(); // what leases ended since kept over the size
    lock.unlock();
    // Outside the lock: a file whose stat changed is hashed again.
    if (auto ok = s.verify(id, package, models); !ok) {
      lease.reset();
      spdlog::error("package {}: refused for launch {}: {}; dropped from the "
                    "cache, the next "
                    "launch fetches it again",
                    id, launch, ok.error().message);
      lock.lock();
      s.drop_locked(id);
      return protocol::call_error(Status::Failed,
                                  fmt::format("{}; dropped from the node's cache, the next "
                                              "launch fetches it again",
                                              ok.error().message));
    }
    return lease;
  }
  s.fetching[id] = true;
  // Whatever becomes of the fetch, even an exception, the callers waiting for
  // it go on.
  struct Fetched {
    State &s;
    const std::string &id;
    std::unique_lock<std::mutex> &lock;
    ~Fetched() {
      if (!lock.owns_lock())
        lock.lock();
      s.fetching.erase(id);
      s.fetched_cv.notify_all();
    }
  } done{s, id, lock};
  lock.unlock();
  auto fetched = s.fetch_into_place(id, package, launch);
  std::map<std::string, std::string> models;
  if (fetched) {
    models = model_hashes(s.root_of(id), package);
    s.seal(id, package, models);
  }
  lock.lock();
  if (!fetched)
    return tl::unexpected(fetched.error());
  s.add_locked(id, package, std::move(models));
  ++s.packages[id].leases;
  s.evict_locked();
  return std::make_shared<CachedPackage>(state_, id);
}

CacheCounts PackageCache::counts() const {
  std::lock_guard lock(state_->mutex);
  return state_->counts;
}

} // namespace rsca::node
