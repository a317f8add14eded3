// The node's package cache (node/package_cache.hpp) against a fake domain that serves file.read
// from memory, and can serve wrong bytes, fewer bytes or no reply: a package is fetched once,
// verified, laid out read-only, reused, evicted least recently used first but never while in use,
// and a failed fetch leaves nothing behind.
#include "node/package_cache.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>

#include "content/sha256.hpp"
#include "protocol/codec.hpp"
#include "temp_dir.hpp"

using namespace rsca;
using Catch::Matchers::Contains;
namespace fs = std::filesystem;

namespace {

using Json = nlohmann::json;

// The domain's FileManager, as the cache sees it.
class FakeDomain {
public:
  enum class Fault { None, WrongBytes, ShortPiece, NoReply };

  protocol::PackageFile add(const std::string &path, std::string bytes, bool executable = false) {
    const auto hash = content::sha256_hex(bytes);
    std::lock_guard lock(mutex_);
    files_[hash] = std::move(bytes);
    return {path, hash, files_[hash].size(), executable};
  }
  void fault(Fault f) { fault_ = f; }
  std::uint64_t bytes_read() const { return bytes_read_; }

  node::FetchPiece fetch() {
    return [this](const protocol::file::ReadRequest &r) {
      std::promise<protocol::CallResult<Json>> reply;
      reply.set_value(answer(r));
      return reply.get_future();
    };
  }

private:
  protocol::CallResult<Json> answer(const protocol::file::ReadRequest &r) {
    if (fault_ == Fault::NoReply)
      return protocol::call_error(protocol::Status::Timeout, "no reply in time");
    std::string bytes;
    {
      std::lock_guard lock(mutex_);
      auto it = files_.find(r.sha256);
      if (it == files_.end())
        return protocol::call_error(protocol::Status::NotFound, "no such file");
      bytes = it->second;
    }
    const auto size = bytes.size();
    std::string piece = bytes.substr(r.offset, r.length);
    if (fault_ == Fault::WrongBytes && !piece.empty())
      piece[0] = static_cast<char>(piece[0] ^ 0x55);
    if (fault_ == Fault::ShortPiece && !piece.empty())
      piece.pop_back();
    bytes_read_ += piece.size();
    return protocol::encode(protocol::file::ReadReply{
        protocol::Bytes(protocol::Bytes::container_type(piece.begin(), piece.end())), size, {}});
  }

  std::mutex mutex_;
  std::map<std::string, std::string> files_;
  std::atomic<Fault> fault_{Fault::None};
  std::atomic<std::uint64_t> bytes_read_{0};
};

std::string bytes_of_size(std::size_t n, char seed) {
  std::string s(n, '\0');
  for (std::size_t i = 0; i < n; ++i)
    s[i] = static_cast<char>(seed + static_cast<char>(i * 31));
  return s;
}

std::string read(const fs::path &file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::size_t entries(const fs::path &dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto &e : fs::directory_iterator(dir))
    ++n;
  return n;
}

struct Fixture {
  test::TempDir dir;
  FakeDomain domain;
  std::unique_ptr<node::PackageCache> cache;

  void open(std::uint64_t max_bytes = 1ULL << 30U) {
    node::CacheOptions options;
    options.dir = dir.path() / "cache";
    options.max_bytes = max_bytes;
    options.piece_timeout = std::chrono::milliseconds(500);
    auto opened = node::PackageCache::open(options, domain.fetch());
    REQUIRE(opened.has_value());
    cache = std::move(*opened);
  }
  protocol::Package package(std::size_t code_bytes, char seed) {
    protocol::Package p{"/srv/repo",
                        {domain.add("apps/A/C/C.spd.xml", "<softpkg/>"),
                         domain.add("apps/A/C/run", bytes_of_size(code_bytes, seed), true)},
                        {}};
    protocol::sort_files(p);
    return p;
  }
  bool nothing_left() const {
    return entries(dir.path() / "cache" / "incoming") == 0 &&
           entries(dir.path() / "cache" / "packages") == cache->counts().packages;
  }
  // The packages on disk, counted by the folder alone: a package kept half written and counted
  // by the cache too would leave nothing_left() true.
  std::size_t packages_on_disk() const { return entries(dir.path() / "cache" / "packages"); }
};

} // namespace

TEST_CASE("package cache: a package is fetched in pieces, verified, laid out read-only and reused",
          "[package]") {
  Fixture f;
  f.open();
  // Three pieces and a bit: more than the pieces asked for at once.
  const auto package = f.package(3 * protocol::file::kMaxReadBytes + 5, 'x');
  auto lease = f.cache->acquire(package, "launch-1");
  REQUIRE(lease.has_value());
  const fs::path run = (*lease)->root() / "apps/A/C/run";
  CHECK(read(run) == bytes_of_size(3 * protocol::file::kMaxReadBytes + 5, 'x'));
  CHECK((fs::status(run).permissions() & fs::perms::owner_exec) != fs::perms::none);
  CHECK((fs::status(run).permissions() & fs::perms::owner_write) == fs::perms::none);
  CHECK(f.cache->counts().fetched == 1);
  const auto read_once = f.domain.bytes_read();
  CHECK(read_once == package.files[0].size + package.files[1].size);

  auto again = f.cache->acquire(package, "launch-2");
  REQUIRE(again.has_value());
  CHECK((*again)->root() == (*lease)->root());
  CHECK(f.domain.bytes_read() == read_once); // nothing fetched again
  CHECK(f.cache->counts().reused == 1);
  CHECK(f.nothing_left());
}

TEST_CASE("package cache: a file already cached in another package is linked, not fetched",
          "[package]") {
  Fixture f;
  f.open();
  const auto first = f.package(4096, 'a');
  REQUIRE(f.cache->acquire(first, "").has_value());
  const auto before = f.domain.bytes_read();
  auto second = first;
  second.files.push_back(f.domain.add("apps/A/D/other", "more"));
  protocol::sort_files(second);
  REQUIRE(f.cache->acquire(second, "").has_value());
  CHECK(f.domain.bytes_read() - before == 4); // only the new file
}

TEST_CASE("package cache: bytes that do not hash to the package's hash are refused, and nothing "
          "is kept",
          "[package]") {
  Fixture f;
  f.open();
  f.domain.fault(FakeDomain::Fault::WrongBytes);
  auto lease = f.cache->acquire(f.package(100000, 'v'), "");
  REQUIRE_FALSE(lease.has_value());
  CHECK_THAT(lease.error().message, Contains("verification failed"));
  CHECK(f.cache->counts().packages == 0);
  CHECK(f.nothing_left());
  CHECK(f.packages_on_disk() == 0);
}

TEST_CASE("package cache: a transfer cut off (fewer bytes, no reply) fails and keeps nothing",
          "[package]") {
  for (auto fault : {FakeDomain::Fault::ShortPiece, FakeDomain::Fault::NoReply}) {
    Fixture f;
    f.open();
    f.domain.fault(fault);
    auto lease = f.cache->acquire(f.package(100000, 'c'), "");
    REQUIRE_FALSE(lease.has_value());
    CHECK_THAT(lease.error().message, Contains("transfer cut off"));
    CHECK(f.nothing_left());
    CHECK(f.packages_on_disk() == 0); // none was there before
    CHECK(f.cache->counts().packages == 0);
    // The domain is fine again: the next launch fetches it whole.
    f.domain.fault(FakeDomain::Fault::None);
    CHECK(f.cache->acquire(f.package(100000, 'c'), "").has_value());
  }
}

TEST_CASE("package cache: a package from the network with a path out of the package is refused "
          "before anything is written",
          "[package]") {
  Fixture f;
  f.open();
  auto package = f.package(10, 'p');
  package.files[0].path = "../../escape";
  protocol::sort_files(package);
  auto lease = f.cache->acquire(package, "");
  REQUIRE_FALSE(lease.has_value());
  CHECK(lease.error().status == protocol::Status::BadRequest);
  CHECK_FALSE(fs::exists(f.dir.path() / "escape"));
  CHECK(f.domain.bytes_read() == 0);
}

TEST_CASE("package cache: over its size it evicts the least recently used package, never one in "
          "use",
          "[package]") {
  Fixture f;
  f.open(/*max_bytes=*/250000); // room for two packages of ~100 kB
  const auto a = f.package(100000, 'a');
  const auto b = f.package(100000, 'b');
  const auto c = f.package(100000, 'c');
  auto in_use = f.cache->acquire(a, "");
  REQUIRE(in_use.has_value());
  REQUIRE(f.cache->acquire(b, "").has_value()); // its lease ends at once
  REQUIRE(f.cache->acquire(c, "").has_value());
  // a is in use and c is newest: b went.
  CHECK(f.cache->counts().packages == 2);
  CHECK(fs::exists((*in_use)->root()));
  const auto before = f.domain.bytes_read();
  REQUIRE(f.cache->acquire(b, "").has_value()); // fetched again; now c is the oldest unused
  CHECK(f.domain.bytes_read() > before);
  CHECK(f.cache->counts().packages == 2);
  CHECK(fs::exists((*in_use)->root()));
}

TEST_CASE("package cache: callers asking for one package at once fetch it once", "[package]") {
  Fixture f;
  f.open();
  const auto package = f.package(2 * protocol::file::kMaxReadBytes, 'm');
  std::vector<std::thread> threads;
  std::atomic<int> ok{0};
  for (int i = 0; i < 4; ++i)
    threads.emplace_back([&] { ok += f.cache->acquire(package, "").has_value() ? 1 : 0; });
  for (auto &t : threads)
    t.join();
  CHECK(ok == 4);
  CHECK(f.cache->counts().fetched == 1);
  CHECK(f.domain.bytes_read() == package.files[0].size + package.files[1].size);
}

TEST_CASE("package cache: a node that starts again finds its packages, and removes what a node "
          "left half done",
          "[package]") {
  Fixture f;
  f.open();
  const auto package = f.package(1000, 'r');
  REQUIRE(f.cache->acquire(package, "").has_value());
  f.cache.reset();
  // A fetch a dead node left (no such pid), and a package whose manifest was never written.
  const fs::path cache = f.dir.path() / "cache";
  fs::create_directories(cache / "incoming" / "abc.999999999.1" / "x");
  fs::create_directories(cache / "packages" / std::string(64, 'd'));
  f.open();
  CHECK(f.cache->counts().packages == 1);
  CHECK(entries(cache / "incoming") == 0);
  CHECK(entries(cache / "packages") == 1);
  const auto before = f.domain.bytes_read();
  REQUIRE(f.cache->acquire(package, "").has_value());
  CHECK(f.domain.bytes_read() == before);
}

TEST_CASE("package cache: the same bytes executable in one package and not in another keep each "
          "package's mode",
          "[package]") {
  Fixture f;
  f.open();
  protocol::Package plain{"/srv/repo", {f.domain.add("apps/A/data.sh", "echo hi", false)}, {}};
  protocol::Package runnable{"/srv/repo", {f.domain.add("apps/B/run.sh", "echo hi", true)}, {}};
  auto a = f.cache->acquire(plain, "");
  auto b = f.cache->acquire(runnable, "");
  REQUIRE(a.has_value());
  REQUIRE(b.has_value());
  auto mode = [](const fs::path &p) { return fs::status(p).permissions() & fs::perms::owner_exec; };
  CHECK(mode((*a)->root() / "apps/A/data.sh") == fs::perms::none);
  CHECK(mode((*b)->root() / "apps/B/run.sh") != fs::perms::none);
}

namespace {

// Changes one byte of a cached file in place, at the same size, as a disk fault or a hand would.
void change_a_byte(const fs::path &file, std::size_t at) {
  fs::permissions(file, fs::perms::owner_write, fs::perm_options::add);
  std::fstream io(file, std::ios::in | std::ios::out | std::ios::binary);
  io.seekg(static_cast<std::streamoff>(at));
  const char was = static_cast<char>(io.get());
  io.seekp(static_cast<std::streamoff>(at));
  io.put(static_cast<char>(was ^ 0x01));
}

// The package's folder after one use that ended.
fs::path used_once(Fixture &f, const protocol::Package &package) {
  auto lease = f.cache->acquire(package, "launch-1");
  REQUIRE(lease.has_value());
  return (*lease)->root();
}

// A use refused names the file and both hashes, and drops the package: nothing of it is left, and
// the next use fetches it again and gets the domain's bytes.
void check_refused_then_fetched_again(Fixture &f, const protocol::Package &package,
                                      const std::string &expected_bytes) {
  const auto run = std::find_if(package.files.begin(), package.files.end(),
                                [](const auto &file) { return file.path == "apps/A/C/run"; });
  REQUIRE(run != package.files.end());
  auto refused = f.cache->acquire(package, "launch-2");
  REQUIRE_FALSE(refused.has_value());
  CHECK_THAT(refused.error().message,
             Contains("apps/A/C/run") && Contains(run->sha256) && Contains("hashes to"));
  CHECK(f.cache->counts().packages == 0);
  CHECK(f.nothing_left());
  const auto before = f.domain.bytes_read();
  auto again = f.cache->acquire(package, "launch-3");
  REQUIRE(again.has_value());
  // The package was dropped as a whole: all of it comes again.
  CHECK(f.domain.bytes_read() - before == package.files[0].size + package.files[1].size);
  CHECK(read((*again)->root() / "apps/A/C/run") == expected_bytes);
}

} // namespace

TEST_CASE("package cache: a cached file changed in place at the same size is refused at its next "
          "use, and fetched again after",
          "[package]") {
  Fixture f;
  f.open();
  const auto package = f.package(5000, 'm');
  const fs::path root = used_once(f, package);
  change_a_byte(root / "apps/A/C/run", 4321);
  CHECK(fs::file_size(root / "apps/A/C/run") == 5000);
  check_refused_then_fetched_again(f, package, bytes_of_size(5000, 'm'));
}

TEST_CASE("package cache: a cached file cut short is refused at its next use", "[package]") {
  Fixture f;
  f.open();
  const auto package = f.package(5000, 't');
  const fs::path root = used_once(f, package);
  fs::permissions(root / "apps/A/C/run", fs::perms::owner_write, fs::perm_options::add);
  fs::resize_file(root / "apps/A/C/run", 4000);
  check_refused_then_fetched_again(f, package, bytes_of_size(5000, 't'));
}

TEST_CASE("package cache: a file changed while the node was down is refused at its first use",
          "[package]") {
  Fixture f;
  f.open();
  const auto package = f.package(5000, 'd');
  const fs::path root = used_once(f, package);
  f.cache.reset();
  change_a_byte(root / "apps/A/C/run", 10);
  f.open();
  check_refused_then_fetched_again(f, package, bytes_of_size(5000, 'd'));
}
