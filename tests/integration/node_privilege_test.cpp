// What a node runs, and as whom (issue 37): a node runs only code of a package its domain
// delivered, as the GPP's run_as user; a name that would be a path is refused by the node itself;
// a node under a low descriptor limit still launches; a user who may not open a node's socket
// is told so by the CLI. Real daemons, requests sent as any peer on the network could send them.
#include <sys/resource.h>

#include <fstream>
#include <sstream>

#include "domain_fixture.hpp"
#include "process/credentials.hpp"

using namespace rsca::test;

namespace {

// A node.execute request of application "Evil", component "shell", that runs `id > proof`
// when its entry point is a shell.
Json evil_request(const fs::path &proof) {
  return {{"application", "Evil"},
          {"component", "shell"},
          {"entrypoint", "/bin/sh"},
          {"args", Json::array({"-c", "id > " + proof.string()})}};
}

Json with(Json request, const Json &fields) {
  request.update(fields);
  return request;
}

void check_refused(const rsca::control::CallResult<Json> &reply, const std::string &saying) {
  INFO((reply ? "started: " + reply->dump() : reply.error().message));
  CHECK_FALSE(reply.has_value());
  if (reply)
    return;
  CHECK(reply.error().status == Status::BadRequest);
  CHECK_THAT(reply.error().message, Catch::Contains(saying));
}

// The processes node `index` lists.
Json processes_of(TestDomain &domain, int index) {
  auto status = domain.call_node(index, "node.status");
  REQUIRE(status.has_value());
  return status->at("processes");
}

// The real uid process `pid` runs as (/proc/PID/status).
long uid_of(long pid) {
  std::ifstream status(fmt::format("/proc/{}/status", pid));
  for (std::string line; std::getline(status, line);)
    if (line.rfind("Uid:", 0) == 0)
      return std::stol(line.substr(4));
  FAIL("no process " << pid);
  return -1;
}

// Whom a node run by root runs components as by default: rsca, else nobody.
uid_t default_component_uid() {
  if (auto rsca = rsca::process::credentials_of("rsca"))
    return rsca->uid;
  auto nobody = rsca::process::credentials_of("nobody");
  REQUIRE(nobody.has_value());
  return nobody->uid;
}

} // namespace

TEST_CASE("node.execute runs no program but one of a package in its cache: a shell sent by any "
          "peer is refused with the reason and never runs",
          "[integration][hostile]") {
  TestDomain domain(1);
  // A real package, as the domain delivered it: a hostile peer may name one too.
  const Json package = delivered_package_of(domain, "rsca-test-faulty").first;
  const fs::path proof = domain.run_dir() / "proof";
  const Json evil = evil_request(proof);
  const std::vector<std::pair<Json, std::string>> refused{
      {evil, "without a package"},
      {with(evil, {{"entrypoint", "sh"}, {"spd_dir", "/bin"}}), "without a package"},
      {with(evil, {{"package", package}}), "absolute"},
      {with(evil, {{"entrypoint", "sh"}, {"package", package}}), "rsca-component-host"},
      {with(evil, {{"entrypoint", "../../../../../../../../bin/sh"},
                   {"spd_dir", "components"},
                   {"package", package}}),
       "outside its package"}};
  for (const auto &[request, saying] : refused) {
    INFO(request.dump());
    check_refused(domain.call_node(1, "node.execute", request), saying);
  }
  CHECK_FALSE(fs::exists(proof));
  CHECK(processes_of(domain, 1).empty());
}

TEST_CASE("names that would be paths on a node are refused by the node, and nothing is made "
          "outside its log folder",
          "[integration][hostile]") {
  TestDomain domain(1);
  // A real package, as the domain delivered it: a hostile peer may name one too.
  const Json package = delivered_package_of(domain, "rsca-test-faulty").first;
  const Json host = {
      {"entrypoint", "rsca-component-host"}, {"args", Json::array()}, {"package", package}};
  for (const auto &[application, component] :
       std::vector<std::pair<std::string, std::string>>{{"../escaped", "c"},
                                                        {"Evil", "../../escaped"},
                                                        {"..", "c"},
                                                        {"Evil", ".hidden"},
                                                        {"a/b", "c"},
                                                        {"Evil", ""}}) {
    INFO(application << " / " << component);
    check_refused(
        domain.call_node(1, "node.execute",
                         with(host, {{"application", application}, {"component", component}})),
        "name");
  }
  CHECK_FALSE(fs::exists(domain.run_dir() / "escaped"));
  CHECK_FALSE(fs::exists(domain.run_dir() / "escaped.log"));
  CHECK_FALSE(fs::exists(domain.run_dir() / "logs" / "a"));
  CHECK(processes_of(domain, 1).empty());
}

TEST_CASE("a node's components run as the GPP's run_as user, rsca or else nobody, and as root "
          "only where the DCD says so",
          "[integration][node]") {
  INFO("only a node run by root changes user: the tests run as root");
  REQUIRE(::geteuid() == 0);
  const auto [dcd, uid] = GENERATE(
      std::pair{kSource / "profiles/dev/nodes/node1/DeviceManager.dcd.xml",
                default_component_uid()},
      // Its GPP executes every process (no fork server).
      std::pair{kTestSdr / "dev/nodes/exec1/DeviceManager.dcd.xml", default_component_uid()},
      std::pair{kTestSdr / "dev/nodes/root1/DeviceManager.dcd.xml", uid_t{0}});
  INFO(dcd);
  TestDomain domain({dcd});
  const auto pids = pids_of(domain.create("Healthy"));
  REQUIRE_FALSE(pids.empty());
  for (const long pid : pids) {
    INFO("pid " << pid);
    CHECK(uid_of(pid) == static_cast<long>(uid));
  }
  // They run as they do as root: registered, started, released, and nothing left behind.
  REQUIRE(domain.call("app.start", Json{{"app", "Healthy"}}).has_value());
  REQUIRE(domain.call("app.release", Json{{"app", "Healthy"}}).has_value());
  domain.require_clean(pids);
}

TEST_CASE("a node under a limit of 64 descriptors launches its components", "[integration][node]") {
  TestDomain domain(1);
  const rlimit limit{64, 64};
  REQUIRE(::prlimit(domain.node_pid(1), RLIMIT_NOFILE, &limit, nullptr) == 0);
  const auto pids = pids_of(domain.create("Healthy"));
  for (const long pid : pids)
    CHECK(process_exists(pid));
  REQUIRE(domain.call("app.release", Json{{"app", "Healthy"}}).has_value());
  domain.require_clean(pids);
}

TEST_CASE("the CLI of a user who may not open a node's socket says so and what to do, and does "
          "not go over DDS instead",
          "[integration][node]") {
  INFO("runs the CLI as nobody: the tests run as root");
  REQUIRE(::geteuid() == 0);
  TestDomain domain(1);
  const fs::path socket = domain.run_dir() / "node1.sock";
  REQUIRE(fs::is_socket(socket));
  const fs::path out = domain.run_dir() / "nobody.out";
  const auto as_nobody = [&](const ChildProcess::Environment &more) {
    auto env = domain.env();
    env.insert(env.end(), more.begin(), more.end());
    // runuser keeps the environment: the CLI finds this domain's run folder and DDS domain.
    ChildProcess cli("/bin/sh",
                     {"-c", "runuser -u nobody -- \"$0\" \"$@\" > " + out.string() + " 2>&1",
                      (kBin / "rsca").string(), "ls", "nodes"},
                     env);
    auto status = cli.wait_exit(60s);
    std::ifstream in(out);
    std::stringstream text;
    text << in.rdbuf();
    return std::pair{status && WIFEXITED(*status) ? WEXITSTATUS(*status) : -1, text.str()};
  };
  const auto [rc, text] = as_nobody({});
  INFO(text);
  CHECK(rc != 0);
  CHECK_THAT(text, Catch::Contains(socket.string()) && Catch::Contains("permission denied") &&
                       Catch::Contains("as root") && Catch::Contains("group"));
  CHECK_THAT(text, !Catch::Contains("node1 "));
  // Where no socket exists, the CLI goes over DDS, as it always did.
  const fs::path empty = domain.run_dir() / "no-sockets";
  fs::create_directories(empty);
  const auto [dds_rc, dds_text] = as_nobody({{"RSCA_RUN_DIR", empty.string()}});
  INFO(dds_text);
  CHECK(dds_rc == 0);
  CHECK_THAT(dds_text, Catch::Contains("node1"));
}
