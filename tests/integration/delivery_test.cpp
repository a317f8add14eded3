// Code delivered to the node (issue 21): a node runs each component process inside its package,
// fetched from the domain's FileManager into the node's cache when first needed, verified, and
// reused by later launches; a file that fails verification fails the launch at execute, rolls it
// back, and leaves nothing in the cache. Real daemons and processes; the files are the build's.
// Issue 37: what a node gets of a component's code is the executable without its debug
// information, compressed on the wire, yet the process runs, and the domain keeps the full file
// where gdb finds it by build id (the ELF files are read here with <elf.h> alone, not with the
// domain's reader); a cached executable that changed on its node is refused at the next launch
// with the reason, nothing of that launch left running, and fetched again by the one after.
#include <elf.h>
#include <fcntl.h>
#include <sys/stat.h>

#include <fstream>

#include "domain_fixture.hpp"

using namespace rsca::test;
using namespace std::chrono_literals;
using Catch::Matchers::Contains;
using rsca::control::Json;

namespace {

const std::string kProducerConsumer =
    (kSource / "profiles/dom/waveforms/ProducerConsumer/ProducerConsumer.sad.xml").string();

// The detail of the launch's execute step, from `rsca --json launch`'s output.
std::string execute_detail(const std::string &out) {
  const auto json = Json::parse(out, nullptr, false);
  if (json.is_discarded() || !json.contains("launch"))
    return {};
  for (const auto &step : json.at("launch").at("steps"))
    if (step.at("step") == "execute")
      return step.at("detail").get<std::string>();
  return {};
}

Json cache_of(TestDomain &domain, int node) {
  auto status = domain.call_node(node, "node.status");
  REQUIRE(status.has_value());
  REQUIRE(status->contains("cache"));
  return status->at("cache");
}

std::string content_of(const fs::path &file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The section names of a 64-bit ELF file, and its GNU build id (hex); empty when not one.
struct Sections {
  std::vector<std::string> names;
  std::string build_id;
  bool has(const std::string &name) const {
    return std::find(names.begin(), names.end(), name) != names.end();
  }
};

Sections sections_of(const fs::path &file) {
  const std::string bytes = content_of(file);
  Sections out;
  Elf64_Ehdr header{};
  if (bytes.size() < sizeof header)
    return out;
  std::memcpy(&header, bytes.data(), sizeof header);
  if (std::memcmp(header.e_ident, ELFMAG, SELFMAG) != 0 ||
      header.e_shoff + header.e_shnum * sizeof(Elf64_Shdr) > bytes.size())
    return out;
  std::vector<Elf64_Shdr> shdrs(header.e_shnum);
  std::memcpy(shdrs.data(), bytes.data() + header.e_shoff, shdrs.size() * sizeof(Elf64_Shdr));
  const auto &names = shdrs.at(header.e_shstrndx);
  for (const auto &s : shdrs) {
    out.names.emplace_back(bytes.data() + names.sh_offset + s.sh_name);
    if (out.names.back() == ".note.gnu.build-id") {
      Elf64_Nhdr note{};
      std::memcpy(&note, bytes.data() + s.sh_offset, sizeof note);
      const auto *id = bytes.data() + s.sh_offset + sizeof note + ((note.n_namesz + 3U) & ~3U);
      for (std::size_t i = 0; i < note.n_descsz; ++i)
        out.build_id += fmt::format("{:02x}", static_cast<unsigned char>(id[i]));
    }
  }
  return out;
}

// The cached copy of `name` on `node`'s cache (the first found).
fs::path cached(TestDomain &domain, const std::string &node, const std::string &name) {
  const fs::path packages = domain.run_dir() / "cache" / node / "packages";
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(packages, ec); !ec && it != fs::end(it);
       it.increment(ec))
    if (it->path().filename() == name && it->is_regular_file())
      return it->path();
  return {};
}

std::size_t entries(const fs::path &dir) {
  std::size_t n = 0;
  std::error_code ec;
  for (auto it = fs::directory_iterator(dir, ec); !ec && it != fs::directory_iterator();
       it.increment(ec))
    ++n;
  return n;
}

} // namespace

TEST_CASE("a component's files are delivered to its node once: verified, run from the node's "
          "cache, reused by the next launch",
          "[integration][delivery]") {
  DefaultDelivery compressed; // also under the sanitizers
  TestDomain domain;
  auto [rc, out] = domain.cli({"--json", "launch", kProducerConsumer});
  INFO(out);
  REQUIRE(rc == 0);
  CHECK_THAT(execute_detail(out), Contains("delivered"));
  auto cache = cache_of(domain, 1);
  CHECK(cache.at("fetched") == 2); // both components placed on node1 (pack)
  // What runs of the build's files (their debug information stays with the domain).
  const auto built = fs::file_size(kBin / "rsca-producer") + fs::file_size(kBin / "rsca-consumer");
  const auto fetched = cache.at("fetched_bytes").get<std::uint64_t>();
  CHECK(fetched > 0);
  CHECK(fetched <= built + 64 * 1024); // the executables and their profiles
  CHECK(cache.at("reused") == 0);

  // Each process runs the copy in the node's cache, not the build's.
  const fs::path packages = domain.run_dir() / "cache" / "node1" / "packages";
  auto shown = domain.call("app.show", Json{{"app", "ProducerConsumer"}});
  REQUIRE(shown.has_value());
  const auto pids = pids_of(*shown);
  for (long pid : pids) {
    const auto exe = fs::read_symlink(fmt::format("/proc/{}/exe", pid));
    INFO(exe);
    CHECK(exe.string().rfind(packages.string(), 0) == 0);
  }

  auto [rc2, out2] = domain.cli({"--json", "launch", "ProducerConsumer", "--name", "Again"});
  INFO(out2);
  REQUIRE(rc2 == 0);
  CHECK_THAT(execute_detail(out2), !Contains("delivered"));
  cache = cache_of(domain, 1);
  CHECK(cache.at("fetched") == 2);
  CHECK(cache.at("reused") == 2);

  // On node2, whose cache is empty, the launch's progress counts what its node fetched.
  auto on_node2 =
      domain.call("app.create",
                  Json{{"application", "ProducerConsumer"},
                       {"name", "OnNode2"},
                       {"launch_id", "delivery-test-node2"},
                       {"assign", {{"Producer_1", "node2:GPP_1"}, {"Consumer_1", "node2:GPP_1"}}}});
  INFO((on_node2 ? std::string() : on_node2.error().message));
  REQUIRE(on_node2.has_value());
  auto progress = domain.call("app.progress", Json{{"launch_id", "delivery-test-node2"}});
  REQUIRE(progress.has_value());
  CHECK(progress->value("delivered_bytes", std::uint64_t{0}) >= fetched);
  // Compressed on the wire.
  CHECK(progress->value("delivered_wire_bytes", fetched) < fetched);

  auto all = pids;
  for (const char *name : {"Again", "OnNode2"}) {
    auto shown_app = domain.call("app.show", Json{{"app", name}});
    REQUIRE(shown_app.has_value());
    for (long pid : pids_of(*shown_app))
      all.push_back(pid);
  }
  for (const char *name : {"ProducerConsumer", "Again", "OnNode2"})
    REQUIRE(domain.call("app.release", Json{{"app", name}}).has_value());
  domain.require_clean(all);
}

TEST_CASE("a component's shared-library dependency is delivered with it, and its folder is on "
          "the process's LD_LIBRARY_PATH",
          "[integration][delivery]") {
  TestDomain domain;
  domain.install("WithLibrary");
  auto [rc, out] = domain.cli({"--json", "launch", "WithLibrary"});
  INFO(out);
  REQUIRE(rc == 0);
  auto shown = domain.call("app.show", Json{{"app", "WithLibrary"}});
  REQUIRE(shown.has_value());
  const auto pids = pids_of(*shown);
  REQUIRE(pids.size() == 1);
  // The process's environment, as the node gave it (NUL-separated).
  std::ifstream in(fmt::format("/proc/{}/environ", pids.front()), std::ios::binary);
  const std::string variables((std::istreambuf_iterator<char>(in)),
                              std::istreambuf_iterator<char>());
  std::string path;
  for (std::size_t at = 0; at < variables.size();) {
    const std::size_t end = std::min(variables.find('\0', at), variables.size());
    if (const std::string entry = variables.substr(at, end - at);
        entry.starts_with("LD_LIBRARY_PATH="))
      path = entry.substr(std::string("LD_LIBRARY_PATH=").size());
    at = end + 1;
  }
  INFO(path);
  const std::string first = path.substr(0, path.find(':'));
  // The first folder is the dependency's, inside a package of the node's cache, and holds the
  // library.
  const fs::path packages = domain.run_dir() / "cache" / "node1" / "packages";
  CHECK(first.rfind(packages.string(), 0) == 0);
  CHECK(fs::path(first).filename() == "lib");
  CHECK(fs::exists(fs::path(first) / "librsca-testlib.so"));
  REQUIRE(domain.call("app.release", Json{{"app", "WithLibrary"}}).has_value());
  domain.require_clean(pids);
}

TEST_CASE("a file that fails verification on its node fails the launch at execute, rolls it back, "
          "and leaves nothing in the node's cache",
          "[integration][delivery][failure]") {
  const ColdCaches cold; // the consumer's good bytes must not be in node2's cache already
  TestDomain domain;
  // The domain finds the components' code in a folder of this test's, whose copy it then alters.
  const fs::path bin = domain.run_dir() / "bin";
  fs::create_directories(bin);
  for (const char *name : {"rsca-producer", "rsca-consumer"})
    fs::copy_file(kBin / name, bin / name);
  domain.use_exec_path({bin});
  // A launch on node1 has the domain hash the copies.
  auto [rc, out] = domain.cli({"launch", kProducerConsumer});
  INFO(out);
  REQUIRE(rc == 0);
  REQUIRE(domain.call("app.release", Json{{"app", "ProducerConsumer"}}).has_value());

  // What the domain serves of the consumer changes but keeps its size and modification time (as
  // `cp -p` of another build of the same size would): the domain's stamp cannot tell, the node's
  // hash does. That is the copy without debug information the domain made (.delivered/) when the
  // build has it, else the file itself; every copy there changes.
  std::vector<fs::path> served{bin / "rsca-consumer"};
  std::error_code ec;
  for (auto it = fs::directory_iterator(domain.run_dir() / "repository" / ".delivered", ec);
       !ec && it != fs::directory_iterator(); it.increment(ec))
    served.push_back(it->path());
  for (const auto &file : served) {
    struct stat before {};
    REQUIRE(::stat(file.c_str(), &before) == 0);
    {
      std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
      f.seekp(-1, std::ios::end);
      f.put('\x5a');
    }
    const struct timespec times[2] = {before.st_atim, before.st_mtim};
    REQUIRE(::utimensat(AT_FDCWD, file.c_str(), times, 0) == 0);
  }

  auto [rc2, out2] = domain.cli(
      {"launch", "ProducerConsumer", "--name", "Altered", "--assign", "Consumer_1=node2:GPP_1"});
  INFO(out2);
  CHECK(rc2 == 6);
  CHECK_THAT(out2, Contains("failed at step 'execute'"));
  CHECK_THAT(out2, Contains("verification failed"));
  CHECK_THAT(out2, Contains("rolled back"));
  domain.require_clean({});
  CHECK(TestDomain::wait_for([&] { return domain.running_pids().empty(); }));
  // The producer's package (packed onto node2 with the consumer) may be there, whole; nothing of
  // the consumer's is, and nothing is half done.
  const fs::path cache = domain.run_dir() / "cache" / "node2";
  CHECK(cache_of(domain, 2).at("packages") == entries(cache / "packages"));
  CHECK(entries(cache / "incoming") == 0);
  for (const auto &entry : fs::recursive_directory_iterator(cache))
    CHECK(entry.path().filename() != "rsca-consumer");
}

// Healthy runs the Producer, which rsca_add_component builds with its debug information split off
// (cmake/RscaAddComponent.cmake), and the test component Faulty, built as a user might without
// that: the domain strips what the build did not.
// Not under the sanitizers, where stripping and compressing two 140 MB ASan executables took the
// launch 168 s, past every bound: there the file manager's unit tests cover the strip.
#ifdef RSCA_SANITIZE
#define RSCA_NOT_UNDER_SANITIZERS "[.]"
#else
#define RSCA_NOT_UNDER_SANITIZERS ""
#endif
TEST_CASE("a delivered executable has no debug sections yet runs, the domain keeps its debug "
          "file by build id, and the launch says the bytes delivered",
          "[integration][delivery]" RSCA_NOT_UNDER_SANITIZERS) {
  const auto built_faulty = sections_of(kBin / "rsca-test-faulty");
  REQUIRE(built_faulty.has(".debug_info")); // a build with debug information, as the issue's
  REQUIRE_FALSE(built_faulty.build_id.empty());
  DefaultDelivery stripped; // also under the sanitizers
  TestDomain domain;
  const std::string healthy = (kTestSdr / "dom/waveforms/Healthy/Healthy.sad.xml").string();
  auto [rc, out] = domain.cli({"--json", "launch", "--sdrroot", kTestSdr.string(), healthy});
  INFO(out);
  REQUIRE(rc == 0);
  // "… MB of their files delivered (… MB on the wire)": far less than the build's files.
  const std::string detail = execute_detail(out);
  CHECK_THAT(detail, Contains("delivered") && Contains("on the wire"));

  // Each process runs a copy without debug sections, of the build's code (the same build id).
  auto shown = domain.call("app.show", Json{{"app", "Healthy"}});
  REQUIRE(shown.has_value());
  const auto pids = pids_of(*shown);
  REQUIRE(pids.size() == 2);
  std::uintmax_t built_bytes = 0;
  for (long pid : pids) {
    const fs::path exe = fs::read_symlink(fmt::format("/proc/{}/exe", pid));
    INFO(exe);
    const auto delivered = sections_of(exe);
    CHECK(delivered.has(".text"));
    CHECK_FALSE(delivered.has(".debug_info"));
    CHECK(delivered.build_id == sections_of(kBin / exe.filename()).build_id);
    built_bytes += fs::file_size(kBin / exe.filename());
  }
  const auto cache = domain.call_node(1, "node.status");
  REQUIRE(cache.has_value());
  CHECK(cache->at("cache").at("fetched_bytes").get<std::uint64_t>() < built_bytes / 4);

  // Faulty's full file, debug sections and all, where the docs say gdb finds it.
  const fs::path debug = domain.run_dir() / "repository" / ".build-id" /
                         built_faulty.build_id.substr(0, 2) /
                         (built_faulty.build_id.substr(2) + ".debug");
  INFO(debug);
  REQUIRE(fs::exists(debug));
  CHECK(sections_of(debug).has(".debug_info"));
  CHECK(sections_of(debug).build_id == built_faulty.build_id);

  REQUIRE(domain.call("app.release", Json{{"app", "Healthy"}}).has_value());
  domain.require_clean(pids);
}

TEST_CASE("a cached executable changed on its node is refused at the next launch with the "
          "reason, nothing of it left running, and fetched again by the launch after",
          "[integration][delivery][failure]") {
  const ColdCaches cold; // its node's cache must hold no other copy of the producer
  TestDomain domain;
  auto [rc, out] = domain.cli({"launch", kProducerConsumer});
  INFO(out);
  REQUIRE(rc == 0);
  REQUIRE(domain.call("app.release", Json{{"app", "ProducerConsumer"}}).has_value());
  REQUIRE(TestDomain::wait_for([&] { return domain.running_pids().empty(); }));

  // The cached producer is replaced by one of its size and mode with one byte changed (in place
  // it cannot be while its fork server runs it: ETXTBSY; the unit tests change bytes in place).
  const fs::path producer = cached(domain, "node1", "rsca-producer");
  REQUIRE_FALSE(producer.empty());
  const std::string good = content_of(producer);
  std::string changed = good;
  changed[changed.size() / 2] = static_cast<char>(changed[changed.size() / 2] ^ 0x01);
  const fs::path replacement = fs::path(producer).concat(".changed");
  {
    std::ofstream file(replacement, std::ios::binary);
    file << changed;
  }
  fs::permissions(replacement, fs::status(producer).permissions(), fs::perm_options::replace);
  fs::rename(replacement, producer);
  REQUIRE((content_of(producer) == changed)); // (( )): no 66 MB strings printed on failure

  auto [rc2, out2] = domain.cli({"launch", "ProducerConsumer", "--name", "Changed"});
  INFO(out2);
  CHECK(rc2 == 6);
  CHECK_THAT(out2, Contains("failed at step 'execute'") && Contains("rsca-producer") &&
                       Contains("changed since it was verified") && Contains("hashes to") &&
                       Contains("rolled back"));
  CHECK(TestDomain::wait_for([&] { return domain.running_pids().empty(); }));
  domain.require_clean({});

  // The next launch fetches the producer again, and runs the domain's bytes.
  auto [rc3, out3] = domain.cli({"--json", "launch", "ProducerConsumer", "--name", "Again"});
  INFO(out3);
  REQUIRE(rc3 == 0);
  CHECK_THAT(execute_detail(out3), Contains("delivered"));
  const fs::path again = cached(domain, "node1", "rsca-producer");
  REQUIRE_FALSE(again.empty());
  CHECK((content_of(again) == good)); // (( )): no 66 MB strings printed on failure
  auto shown = domain.call("app.show", Json{{"app", "Again"}});
  REQUIRE(shown.has_value());
  const auto pids = pids_of(*shown);
  REQUIRE(domain.call("app.release", Json{{"app", "Again"}}).has_value());
  domain.require_clean(pids);
}
