// The daemons as systemd Type=notify services (tools/systemd): each tells its service manager
// READY=1 only once it serves, says what it does on the way (STATUS=), and STOPPING=1 on SIGTERM
// before it exits cleanly. The test is the service manager: it owns the NOTIFY_SOCKET.
#include <csignal>

#include "service_fixture.hpp"

namespace {

using namespace rsca::test;

// Stops `daemon` as systemd does (SIGTERM) and checks it says so and exits 0.
void stop_as_systemd_does(ChildProcess &daemon, DatagramSocket &notify) {
  daemon.signal(SIGTERM);
  auto stopping = notify.wait_for([](const auto &m) { return assigns(m, "STOPPING=1"); }, 10s);
  REQUIRE(stopping.has_value());
  CHECK(stopping->pid == daemon.pid());
  CHECK_THAT(value_of(*stopping, "STATUS"), Catch::Contains("stopping"));
  const auto status = daemon.wait_exit(20s);
  INFO(ChildProcess::describe(status));
  CHECK((status && WIFEXITED(*status) && WEXITSTATUS(*status) == 0));
}

// The STATUS= values a daemon sent, in order.
std::vector<std::string> statuses(const DatagramSocket &notify) {
  std::vector<std::string> out;
  for (const auto &m : notify.received())
    if (auto s = value_of(m, "STATUS"); !s.empty())
      out.push_back(s);
  return out;
}

} // namespace

TEST_CASE("rsca-domaind tells systemd it is ready once its store is open and it serves, and "
          "that it stops on SIGTERM") {
  ServiceRun run;
  DatagramSocket notify(run.dir() / "domaind.notify");
  const auto log = run.dir() / "domaind.log";
  auto domaind = run.start(run.domaind_args(), {{"NOTIFY_SOCKET", notify.path().string()}}, log);
  const auto ready = wait_ready(notify, *domaind);

  // At READY=1 the store is there and the daemon has said it serves: it told the truth.
  CHECK(rsca::test::fs::exists(run.dir() / "repository/domain.sqlite"));
  const std::string logged = read_file(log);
  INFO(logged);
  CHECK_THAT(logged, Catch::Contains("serving at rsca/domain"));
  CHECK_THAT(value_of(ready, "STATUS"), Catch::StartsWith("serving domain rsca"));
  const auto said = statuses(notify);
  INFO(fmt::format("{}", fmt::join(said, " | ")));
  REQUIRE(said.size() >= 2);
  CHECK_THAT(said[said.size() - 2], Catch::StartsWith("opening the domain store"));
  // ... and a request is answered.
  auto nodes = run.client().call_sync("rsca/domain", "domain.nodes", Json::object(), 10s);
  INFO((nodes ? nodes->dump() : nodes.error().message));
  CHECK(nodes.has_value());
  auto [rc, out] = run.cli({"ls", "nodes"}, {{"RSCA_NODE_SOCKET", "none"}});
  INFO(out);
  CHECK(rc == 0);

  stop_as_systemd_does(*domaind, notify);
}

TEST_CASE("rsca-noded tells systemd it is ready once its devices run, it serves its control "
          "socket and it has announced itself, and that it stops on SIGTERM") {
  ServiceRun run;
  auto domaind = run.start(run.domaind_args(), {}, run.dir() / "domaind.log");
  DatagramSocket notify(run.dir() / "noded.notify");
  const auto log = run.dir() / "noded.log";
  auto noded = run.start(run.noded_args(), {{"NOTIFY_SOCKET", notify.path().string()}}, log);
  const auto ready = wait_ready(notify, *noded);

  {
    const std::string logged = read_file(log);
    INFO(logged);
    CHECK_THAT(logged, Catch::Contains("node node1 announced with 1 device(s)"));
  }
  CHECK_THAT(value_of(ready, "STATUS"), Catch::StartsWith("serving node node1 of domain rsca"));
  // The CLI reaches the domain through the node's control socket, no DDS of its own.
  auto [rc, out] = run.cli({"ls", "nodes"}, {{"RSCA_NODE_SOCKET", run.node_socket().string()}});
  INFO(out);
  CHECK(rc == 0);
  auto status = run.client().call_sync("rsca/node/node1", "node.status", Json::object(), 10s);
  REQUIRE(status.has_value());
  CHECK(status->at("devices").size() == 1);
  // The domain finds it by its announcement (DDS discovery: waited for, bounded).
  CHECK(wait_until(
      [&] {
        auto nodes = run.client().call_sync("rsca/domain", "domain.nodes", Json::object(), 5s);
        return nodes && nodes->at("nodes").size() == 1;
      },
      20s));

  stop_as_systemd_does(*noded, notify);
}
