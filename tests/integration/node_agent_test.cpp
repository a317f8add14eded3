// The node as its host's agent for control (protocol/node_link.hpp), end to end with real
// daemons: a component process started by a node is controlled through the node, and has no DDS
// participant (no UDP socket) unless it has data ports to connect.
#include <catch2/catch.hpp>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "domain_fixture.hpp"

using namespace rsca::test;

namespace {

// The inodes of the UDP sockets this network namespace has (/proc/net/udp and udp6).
std::set<std::string> udp_socket_inodes() {
  std::set<std::string> inodes;
  for (const char *table : {"/proc/net/udp", "/proc/net/udp6"}) {
    std::ifstream in(table);
    std::string line;
    std::getline(in, line); // the header
    while (std::getline(in, line)) {
      std::istringstream fields(line);
      std::string field;
      for (int i = 0; i < 10 && fields >> field; ++i) {
      }
      inodes.insert(field); // the tenth column
    }
  }
  return inodes;
}

// How many UDP sockets process `pid` holds.
int udp_sockets_of(long pid) {
  const auto udp = udp_socket_inodes();
  int count = 0;
  for (const auto &fd : std::filesystem::directory_iterator(fmt::format("/proc/{}/fd", pid))) {
    std::error_code error;
    const auto target = std::filesystem::read_symlink(fd.path(), error).string();
    if (error || !target.starts_with("socket:["))
      continue;
    if (udp.contains(target.substr(8, target.size() - 9)))
      ++count;
  }
  return count;
}

const Json &component_named(const Json &app, const std::string &id) {
  for (const auto &c : app.at("components"))
    if (c.at("id") == id)
      return c;
  FAIL("no component " << id);
  throw std::logic_error("unreachable");
}

// The first connection of `app` as connection.list shows it, once samples flow over it.
Json flowing_connection(TestDomain &domain, const std::string &app) {
  Json connection;
  REQUIRE(TestDomain::wait_for([&] {
    auto list = domain.call("connection.list", Json{{"app", app}});
    REQUIRE(list.has_value());
    connection = list->at("connections").at(0);
    return connection.at("provides_state").value("samples", 0) > 3;
  }));
  return connection;
}

} // namespace

TEST_CASE("a component process with no data ports has no UDP socket: its node serves its control",
          "[integration][node-agent]") {
  TestDomain domain;
  // Supervisor_1 has only a uses port of a control interface; Producer_1 has data ports.
  const Json app = domain.create("Supervised");
  const long supervisor = component_named(app, "Supervisor_1").at("pid").get<long>();
  // The nodes are on DDS: the test can see UDP sockets at all, so the count below is not zero for
  // want of seeing them.
  REQUIRE(udp_sockets_of(domain.node_pid(1)) > 0);
  CHECK(udp_sockets_of(supervisor) == 0);
  // Controlled all the same: its node relays (query, and the supervisor's own calls to the
  // producer's address through the nodes, which its start made).
  auto q = domain.call("app.query", Json{{"app", "Supervised"}, {"component", "Supervisor_1"}});
  REQUIRE(q.has_value());
  auto shown = domain.call("app.show", Json{{"app", "Supervised"}});
  REQUIRE(shown.has_value());
  CHECK(component_named(*shown, "Supervisor_1").at("state") == "running");
  CHECK(udp_sockets_of(supervisor) == 0);
  REQUIRE(domain.call("app.release", Json{{"app", "Supervised"}}).has_value());
  domain.require_clean(pids_of(app));
}

TEST_CASE("two component processes of one node connect through its shared memory, with no UDP "
          "socket of their own",
          "[integration][node-agent]") {
  TestDomain domain(1);
  const auto pids = pids_of(domain.launch_shipped("ProducerConsumer"));
  REQUIRE(pids.size() == 2);
  // Samples flow, end to end, over the node's ring.
  const Json samples = flowing_connection(domain, "ProducerConsumer");
  INFO(samples.dump());
  CHECK(samples.at("uses_state").value("same_host", false));
  CHECK(samples.at("provides_state").value("same_host", false));
  CHECK(samples.at("uses_state").value("matched", 0) == 1);
  CHECK(samples.at("provides_state").value("matched", 0) == 1);
  REQUIRE(udp_sockets_of(domain.node_pid(1)) > 0);
  for (long pid : pids)
    CHECK(udp_sockets_of(pid) == 0);
  auto status = domain.call_node(1, "node.status");
  REQUIRE(status.has_value());
  CHECK(status->at("shared_memory").at("rings") == 1);
  CHECK(status->at("shared_memory").at("ends") == 2);
  REQUIRE(domain.call("app.release", Json{{"app", "ProducerConsumer"}}).has_value());
  domain.require_clean(pids); // with the node's shared memory empty again
}

TEST_CASE("two component processes on two nodes connect through their nodes' relays, with no "
          "socket of their own",
          "[integration][node-agent]") {
  TestDomain domain(2);
  const Json app = domain.launch_shipped("ProducerConsumer", {"--strategy", "spread"});
  const auto pids = pids_of(app);
  REQUIRE(pids.size() == 2);
  REQUIRE(component_named(app, "Producer_1").at("node") !=
          component_named(app, "Consumer_1").at("node"));
  // Samples flow: producer -> node1's ring -> node1's relay -> DDS -> node2's relay -> node2's
  // ring -> consumer. Each end counts the other as matched, as DDS matched the two relays.
  const Json samples = flowing_connection(domain, "ProducerConsumer");
  INFO(samples.dump());
  for (const char *end : {"uses_state", "provides_state"}) {
    CHECK(samples.at(end).value("relayed", false));
    CHECK(samples.at(end).value("matched", 0) == 1);
  }
  REQUIRE(udp_sockets_of(domain.node_pid(1)) > 0);
  for (long pid : pids)
    CHECK(udp_sockets_of(pid) == 0);
  for (int node : {1, 2}) { // a ring, an end and a relay on each
    auto status = domain.call_node(node, "node.status");
    REQUIRE(status.has_value());
    INFO("node" << node << ": " << status->dump());
    CHECK(status->at("shared_memory").at("rings") == 1);
    CHECK(status->at("shared_memory").at("ends") == 1);
    CHECK(status->at("shared_memory").at("relays") == 1);
  }
  REQUIRE(domain.call("app.release", Json{{"app", "ProducerConsumer"}}).has_value());
  domain.require_clean(pids); // with both nodes' rings and relays gone
}

TEST_CASE("a connection that asks for direct DDS takes it on one node too",
          "[integration][node-agent]") {
  TestDomain domain(1);
  domain.install("DirectPair");
  auto [rc, out] = domain.cli({"launch", "DirectPair"});
  INFO(out);
  REQUIRE(rc == 0);
  auto app = domain.call("app.show", Json{{"app", "DirectPair"}});
  REQUIRE(app.has_value());
  const auto pids = pids_of(*app);
  const Json samples = flowing_connection(domain, "DirectPair");
  INFO(samples.dump());
  CHECK_FALSE(samples.at("uses_state").value("same_host", true));
  CHECK_FALSE(samples.at("provides_state").value("same_host", true));
  for (long pid : pids)
    CHECK(udp_sockets_of(pid) > 0); // each its own participant
  auto status = domain.call_node(1, "node.status");
  REQUIRE(status.has_value());
  CHECK(status->at("shared_memory").at("rings") == 0);
  REQUIRE(domain.call("app.release", Json{{"app", "DirectPair"}}).has_value());
  domain.require_clean(pids);
}

TEST_CASE("a connection that asks for a TCP stream takes it between the two processes, on two "
          "nodes, with no DDS socket and no ring",
          "[integration][node-agent][tcp]") {
  TestDomain domain(2);
  domain.install("TcpPair");
  auto [rc, out] = domain.cli({"launch", "TcpPair", "--strategy", "spread"});
  INFO(out);
  REQUIRE(rc == 0);
  auto app = domain.call("app.show", Json{{"app", "TcpPair"}});
  REQUIRE(app.has_value());
  const auto pids = pids_of(*app);
  REQUIRE(pids.size() == 2);
  REQUIRE(component_named(*app, "Producer_1").at("node") !=
          component_named(*app, "Consumer_1").at("node"));
  // Samples flow over the stream; each end counts the other while it is connected.
  const Json samples = flowing_connection(domain, "TcpPair");
  INFO(samples.dump());
  for (const char *end : {"uses_state", "provides_state"}) {
    CHECK_FALSE(samples.at(end).value("same_host", true));
    CHECK_FALSE(samples.at(end).value("relayed", true));
    CHECK(samples.at(end).value("tcp", false));
    CHECK(samples.at(end).value("matched", 0) == 1);
  }
  // `rsca ls connections` says how it travels.
  const auto [ls_rc, listed] = domain.cli({"ls", "connections", "TcpPair"});
  REQUIRE(ls_rc == 0);
  CHECK(listed.find("(TCP stream)") != std::string::npos);
  for (long pid : pids)
    CHECK(udp_sockets_of(pid) == 0); // no DDS participant of its own
  for (int node : {1, 2}) {
    auto status = domain.call_node(node, "node.status");
    REQUIRE(status.has_value());
    CHECK(status->at("shared_memory").at("rings") == 0);
    CHECK(status->at("shared_memory").at("relays") == 0);
  }
  // The reader sees its writer go: the producer's process killed, its consumer counts none.
  const long producer = pid_of(*app, "Producer_1");
  REQUIRE(::kill(static_cast<pid_t>(producer), SIGKILL) == 0);
  CHECK(TestDomain::wait_for([&] {
    auto list = domain.call("connection.list", Json{{"app", "TcpPair"}});
    return list && list->at("connections").at(0).at("provides_state").value("matched", -1) == 0;
  }));
  REQUIRE(domain.call("app.release", Json{{"app", "TcpPair"}}).has_value());
  domain.require_clean(pids);
}

TEST_CASE("the CLI reaches the domain through a node's control socket, with no DDS of its own",
          "[integration][node-agent]") {
  TestDomain domain(2);
  REQUIRE(std::filesystem::is_socket(domain.run_dir() / "node1.sock"));
  // With another discovery tag the CLI could not find the domain daemon on DDS: it answers all
  // the same, because the CLI's calls go over the socket and the node makes them.
  const ChildProcess::Environment elsewhere{{"RSCA_DDS_TAG", "nobody-here"}};
  auto [rc, out] = domain.cli({"--json", "ls", "nodes"}, elsewhere);
  INFO(out);
  REQUIRE(rc == 0);
  CHECK(Json::parse(out).at("nodes").size() == 2);
  // A launch and a release, progress and all, the same way.
  auto [launched, launch_out] = domain.cli(
      {"--json", "launch",
       (kSource / "profiles/dom/waveforms/ProducerConsumer/ProducerConsumer.sad.xml").string()},
      elsewhere);
  INFO(launch_out);
  REQUIRE(launched == 0);
  CHECK(domain.call("app.show", Json{{"app", "ProducerConsumer"}}).has_value());
  auto [released, release_out] = domain.cli({"release", "ProducerConsumer"}, elsewhere);
  INFO(release_out);
  CHECK(released == 0);
  // With the sockets refused (RSCA_NODE_SOCKET=none) the CLI is on DDS, and with the other tag
  // it finds nobody.
  const ChildProcess::Environment no_socket{{"RSCA_DDS_TAG", "nobody-here"},
                                            {"RSCA_NODE_SOCKET", "none"}};
  auto [unreachable, unreachable_out] =
      domain.cli({"--timeout-ms", "500", "ls", "nodes"}, no_socket);
  INFO(unreachable_out);
  CHECK(unreachable != 0);
}

TEST_CASE("with its node's socket gone, the CLI tries the next and then DDS",
          "[integration][node-agent]") {
  TestDomain domain(2);
  domain.kill_node(1); // its socket file stays behind, refusing connections
  REQUIRE(std::filesystem::exists(domain.run_dir() / "node1.sock"));
  auto [rc, out] = domain.cli({"--json", "ls", "nodes"});
  INFO(out);
  CHECK(rc == 0);
  domain.kill_node(2);
  auto [over_dds, dds_out] = domain.cli({"--json", "ls", "nodes"});
  INFO(dds_out);
  CHECK(over_dds == 0); // the domain daemon answers over DDS
}

TEST_CASE("a hung node's socket still accepts, the CLI finds it silent and goes on to the next",
          "[integration][node-agent]") {
  TestDomain domain(2);
  ::kill(domain.node_pid(1), SIGSTOP); // the kernel still accepts on its socket
  // The CLI's own DDS finds no domain (a discovery tag nobody uses): it can be answered only
  // through a node's socket, and node1's (tried first) is silent, so only through node2's.
  auto [rc, out] = domain.cli({"--json", "--timeout-ms", "5000", "ls", "nodes"},
                              {{"RSCA_DDS_TAG", "nobody-" + std::to_string(::getpid())}});
  ::kill(domain.node_pid(1), SIGCONT);
  INFO(out);
  REQUIRE(rc == 0); // through node2, not a timeout waiting on node1
  const auto listed = Json::parse(out, nullptr, false);
  REQUIRE(listed.is_object());
  std::set<std::string> names;
  for (const auto &node : listed.at("nodes"))
    names.insert(node.at("name").get<std::string>());
  CHECK(names.count("node2") == 1);
}
