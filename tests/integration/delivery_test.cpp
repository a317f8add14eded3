// Code delivered to the node (issue 21): a node runs each component process inside its package,
// fetched from the domain's FileManager into the node's cache when first needed, verified, and
// reused by later launches; a file that fails verification fails the launch at execute, rolls it
// back, and leaves nothing in the cache. Real daemons and processes; the files are the build's.
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
  TestDomain domain;
  auto [rc, out] = domain.cli({"--json", "launch", kProducerConsumer});
  INFO(out);
  REQUIRE(rc == 0);
  CHECK_THAT(execute_detail(out), Contains("delivered"));
  auto cache = cache_of(domain, 1);
  CHECK(cache.at("fetched") == 2); // both components placed on node1 (pack)
  CHECK(cache.at("fetched_bytes").get<std::uint64_t>() >=
        fs::file_size(kBin / "rsca-producer") + fs::file_size(kBin / "rsca-consumer"));
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
  CHECK(progress->value("delivered_bytes", std::uint64_t{0}) >=
        fs::file_size(kBin / "rsca-producer") + fs::file_size(kBin / "rsca-consumer"));

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

  // The consumer's copy changes but keeps its size and modification time (as `cp -p` of another
  // build of the same size would): the domain's stamp cannot tell, the node's hash does.
  const fs::path consumer = bin / "rsca-consumer";
  struct stat before {};
  REQUIRE(::stat(consumer.c_str(), &before) == 0);
  {
    std::fstream f(consumer, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(-1, std::ios::end);
    f.put('\x5a');
  }
  const struct timespec times[2] = {before.st_atim, before.st_mtim};
  REQUIRE(::utimensat(AT_FDCWD, consumer.c_str(), times, 0) == 0);

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
