// `rsca domain up --node DCD` beside a domain already up in its run folder (issue 39, item 8):
// the node starts and joins it, the domain and its first nodes run on, and `domain down` stops
// them all.
#include <signal.h>

#include <catch2/catch.hpp>

#include "domain_fixture.hpp"

namespace rsca::test {
namespace {

// The CLI on a domain of this test's own (DDS domain, tag and run folder): exit code and output.
class LocalCli {
public:
  LocalCli()
      : run_(fs::temp_directory_path() /
             fmt::format("rsca-up-{}-{}", getpid(), std::random_device{}())) {
    fs::create_directories(run_);
    env_ = {{"RSCA_DDS_DOMAIN", std::to_string(isolated_domain_id())},
            {"RSCA_DDS_TAG", isolated_tag()},
            {"RSCA_RUN_DIR", run_.string()}};
  }
  // Whatever `domain up` left, killed, also when a check failed before `domain down`.
  ~LocalCli() {
    std::error_code ec;
    for (const auto &entry : fs::directory_iterator(run_, ec))
      if (entry.path().extension() == ".pid")
        if (const long pid = std::atol(read_file(entry.path()).c_str()); pid > 0)
          ::kill(static_cast<pid_t>(pid), SIGKILL);
    fs::remove_all(run_, ec);
  }
  LocalCli(const LocalCli &) = delete;
  LocalCli &operator=(const LocalCli &) = delete;

  std::pair<int, std::string> operator()(const std::vector<std::string> &args) const {
    const fs::path out = run_ / "cli.out";
    std::vector<std::string> sh_args{"-c", "\"$0\" \"$@\" > " + out.string() + " 2>&1",
                                     (kBin / "rsca").string(), "--sdrroot",
                                     (kSource / "profiles").string()};
    sh_args.insert(sh_args.end(), args.begin(), args.end());
    ChildProcess cli("/bin/sh", sh_args, env_);
    const auto status = cli.wait_exit(120s);
    return {status && WIFEXITED(*status) ? WEXITSTATUS(*status) : -1, read_file(out)};
  }
  const fs::path &run() const { return run_; }

private:
  fs::path run_;
  ChildProcess::Environment env_;
};

long pid_in(const fs::path &file) {
  return std::atol(read_file(file).c_str());
}

} // namespace

TEST_CASE("rsca domain up --node adds a node to the domain up in its run folder, and domain down "
          "stops it with the rest",
          "[integration][domain][cli]") {
  const LocalCli rsca;
  auto [up_rc, up_out] = rsca({"domain", "up", "--nodes", "1"});
  INFO(up_out);
  REQUIRE(up_rc == 0);
  const long domaind = pid_in(rsca.run() / "domaind.pid");
  const long node1 = pid_in(rsca.run() / "node1.pid");

  const std::string node2_dcd =
      (kSource / "profiles/dev/nodes/node2/DeviceManager.dcd.xml").string();
  auto [add_rc, add_out] = rsca({"domain", "up", "--node", node2_dcd});
  INFO(add_out);
  CHECK(add_rc == 0);
  CHECK_THAT(add_out, Catch::Contains("1 node(s) added, 2 in all"));
  const long node2 = pid_in(rsca.run() / "node2.pid");
  CHECK(process_exists(node2));
  // The domain and its first node are the same processes.
  CHECK(pid_in(rsca.run() / "domaind.pid") == domaind);
  CHECK(process_exists(domaind));
  CHECK(process_exists(node1));
  auto [ls_rc, ls_out] = rsca({"ls", "nodes"});
  INFO(ls_out);
  CHECK(ls_rc == 0);
  CHECK_THAT(ls_out, Catch::Contains("node1") && Catch::Contains("node2"));

  // The same node again is refused, and the one running stays.
  auto [again_rc, again_out] = rsca({"domain", "up", "--node", node2_dcd});
  INFO(again_out);
  CHECK(again_rc == 5);
  CHECK_THAT(again_out, Catch::Contains("a node node2 is already up"));
  CHECK(process_exists(node2));
  // --nodes with a domain up is still refused, and says how to add a node.
  auto [nodes_rc, nodes_out] = rsca({"domain", "up", "--nodes", "1"});
  INFO(nodes_out);
  CHECK(nodes_rc == 5);
  CHECK_THAT(nodes_out, Catch::Contains("`rsca domain up --node DCD` to add a node"));

  auto [down_rc, down_out] = rsca({"domain", "down"});
  INFO(down_out);
  CHECK(down_rc == 0);
  CHECK_THAT(down_out, Catch::Contains("3 daemon(s) stopped"));
  for (const long pid : {domaind, node1, node2})
    CHECK(TestDomain::wait_for([&] { return !process_exists(pid); }));
}

} // namespace rsca::test
