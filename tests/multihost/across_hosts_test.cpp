// A domain across network hosts (network namespaces joined by a bridge): the domain daemon and
// each node daemon on a host of its own, DDS between them over a real network interface.
#include <catch2/catch.hpp>

#include <algorithm>
#include <csignal>
#include <map>
#include <set>
#include <thread>

#include "hosts_domain.hpp"

using namespace rsca::test;

namespace {

const std::string kProducerConsumer =
    (kSource / "profiles/dom/waveforms/ProducerConsumer/ProducerConsumer.sad.xml").string();

// The state of the connection `id` of `app` as `rsca ls connections` gives it, or null.
Json connection_state(HostsDomain &domain, const std::string &app, const std::string &id) {
  const auto listed = domain.cli(1, {"ls", "connections", app});
  const auto json = listed.json();
  if (listed.rc != 0 || json.is_discarded())
    return nullptr;
  for (const auto &c : json.at("connections")) // json is held: no temporary
    if (c.at("id") == id)
      return c;
  return nullptr;
}

// Whether the consumer's end of `samples` has had data from a matched producer.
bool samples_flow(HostsDomain &domain, const std::string &app = "ProducerConsumer") {
  const auto c = connection_state(domain, app, "samples");
  if (c.is_null() || !c.contains("provides_state"))
    return false;
  const auto &provides = c.at("provides_state");
  return provides.at("matched") == 1 && provides.at("samples").get<int>() > 0;
}

} // namespace

TEST_CASE("ProducerConsumer spread over two network hosts: launched, matched, its data on the wire",
          "[multihost]") {
  // Through the nodes (DDS between their relays), or on a TCP stream between the two processes
  // (transport="tcp": the reader listens on its host's interface, not loopback).
  const bool tcp = GENERATE(false, true);
  const std::string app = tcp ? "TcpPair" : "ProducerConsumer";
  const std::string sad =
      tcp ? (kSource / "tests/data/integration/dom/waveforms/TcpPair/TcpPair.sad.xml").string()
          : kProducerConsumer;
  INFO(app);
  HostsDomain domain(2);
  const int consumer_host = HostsDomain::host_of_node(2);
  const auto received_before = domain.hosts().received_bytes(consumer_host);

  // The CLI on the domain's host, over DDS: nothing of it shares a host with a node.
  const auto launched =
      domain.cli(1, {"launch", sad, "--strategy", "spread"}, HostsDomain::over_dds());
  INFO(launched.out << launched.err);
  REQUIRE(launched.rc == 0);
  std::set<std::string> nodes;
  std::vector<pid_t> pids;
  const auto reply = launched.json();
  for (const auto &c : reply.at("components")) {
    nodes.insert(c.at("node").get<std::string>());
    pids.push_back(c.at("pid").get<pid_t>());
  }
  CHECK(nodes == std::set<std::string>{"node1", "node2"});

  REQUIRE(HostsDomain::wait_for([&] { return samples_flow(domain, app); }));
  // The samples crossed the consumer host's network interface, not a loopback.
  CHECK(domain.hosts().received_bytes(consumer_host) > received_before);

  const auto released = domain.cli(1, {"release", app}, HostsDomain::over_dds());
  INFO(released.out << released.err);
  CHECK(released.rc == 0);
  // Nothing left: no application, and the component processes (one pid space for every host)
  // gone.
  const auto apps = domain.cli(1, {"ls", "apps"});
  REQUIRE(apps.rc == 0);
  CHECK(apps.json().at("applications").empty());
  CHECK(HostsDomain::wait_for([&] {
    return std::none_of(pids.begin(), pids.end(), [](pid_t pid) { return ::kill(pid, 0) == 0; });
  }));
}

TEST_CASE("a host's link down for 5 s and back: its node lost and back, its component reachable "
          "again, the connection carrying data again, nothing twice",
          "[multihost]") {
  // As processes, and as libraries in component hosts (one process for the node's components).
  const std::string app =
      GENERATE(std::string("ProducerConsumer"), std::string("ProducerConsumerHosted"));
  INFO(app);
  HostsDomain domain(2);
  const auto sad = (kSource / fmt::format("profiles/dom/waveforms/{0}/{0}.sad.xml", app)).string();
  const auto launched =
      domain.cli(1, {"launch", sad, "--strategy", "spread"}, HostsDomain::over_dds());
  INFO(launched.out << launched.err);
  REQUIRE(launched.rc == 0);
  const auto reply = launched.json();
  std::map<std::string, pid_t> pid_of;
  int consumer_node = 0;
  for (const auto &c : reply.at("components")) {
    pid_of[c.at("id").get<std::string>()] = c.at("pid").get<pid_t>();
    if (c.at("id") == "Consumer_1")
      consumer_node = c.at("node") == "node1" ? 1 : 2;
  }
  REQUIRE(HostsDomain::wait_for([&] { return samples_flow(domain, app); }));

  // The cable of the consumer's host pulled: the domain (over DDS, on its own host) sees the
  // node lost and its component unreachable, not exited.
  const auto pulled_at = std::chrono::steady_clock::now();
  domain.hosts().set_link(HostsDomain::host_of_node(consumer_node), false);
  auto app_summary = [&] {
    const auto listed =
        domain.cli(1, {"--timeout-ms", "2000", "ls", "apps"}, HostsDomain::over_dds());
    const auto json = listed.json();
    return listed.rc == 0 && !json.is_discarded() && json.at("applications").size() == 1
               ? json.at("applications")[0]
               : Json();
  };
  REQUIRE(HostsDomain::wait_for([&] {
    const auto summary = app_summary();
    return !summary.is_null() &&
           summary.value("unreachable", Json::array()) == Json::array({"Consumer_1"});
  }));
  CHECK(app_summary().at("state") == "degraded");
  CHECK(app_summary().at("exited").empty());
  // Its unreachable component could not follow a stop: refused, said why.
  const auto stopped = domain.cli(1, {"stop", app}, HostsDomain::over_dds());
  CHECK(stopped.rc != 0);
  CHECK_THAT(stopped.out + stopped.err, Catch::Contains("unreachable"));
  // Down for 5 s in all, as the scenario: the time is the scenario, not a wait.
  std::this_thread::sleep_until(pulled_at + 5s);
  domain.hosts().set_link(HostsDomain::host_of_node(consumer_node), true);

  // Back: the component is reachable again in the state it had, nothing exited.
  REQUIRE(HostsDomain::wait_for([&] {
    const auto summary = app_summary();
    return !summary.is_null() && summary.at("state") == "running" &&
           summary.value("unreachable", Json::array()).empty();
  }));
  CHECK(app_summary().at("exited").empty());
  // Data flows again on the one connection there is: the consumer's count grows.
  const auto samples_now = [&] {
    const auto c = connection_state(domain, app, "samples");
    return c.is_null() || !c.contains("provides_state") || c.at("provides_state").is_null()
               ? -1
               : c.at("provides_state").at("samples").get<int>();
  };
  const int after_heal = samples_now();
  REQUIRE(after_heal >= 0);
  CHECK(HostsDomain::wait_for([&] { return samples_now() > after_heal; }));
  const auto listed = domain.cli(1, {"ls", "connections", app});
  REQUIRE(listed.rc == 0);
  CHECK(listed.json().at("connections").size() == 1);
  const auto shown = domain.cli(1, {"show", app}, HostsDomain::over_dds());
  INFO(shown.out << shown.err);
  REQUIRE(shown.rc == 0);
  const auto shown_json = shown.json(); // held: a range-for over a temporary's member dangles
  for (const auto &c : shown_json.at("components")) {
    CHECK(c.at("state") == "running");
    CHECK(c.at("pid").get<pid_t>() == pid_of.at(c.at("id").get<std::string>())); // not twice
  }

  const auto released = domain.cli(1, {"release", app}, HostsDomain::over_dds());
  CHECK(released.rc == 0);
  CHECK(HostsDomain::wait_for([&] {
    return std::none_of(pid_of.begin(), pid_of.end(),
                        [](const auto &p) { return ::kill(p.second, 0) == 0; });
  }));
}

TEST_CASE("an application released while a node is lost: its process there runs on until the "
          "node is back, then is ended",
          "[multihost]") {
  HostsDomain domain(2);
  const auto launched =
      domain.cli(1, {"launch", kProducerConsumer, "--strategy", "spread"}, HostsDomain::over_dds());
  INFO(launched.out << launched.err);
  REQUIRE(launched.rc == 0);
  pid_t consumer = 0;
  int consumer_node = 0;
  std::vector<pid_t> pids;
  const auto reply = launched.json();
  for (const auto &c : reply.at("components")) {
    pids.push_back(c.at("pid").get<pid_t>());
    if (c.at("id") == "Consumer_1") {
      consumer = c.at("pid").get<pid_t>();
      consumer_node = c.at("node") == "node1" ? 1 : 2;
    }
  }
  REQUIRE(consumer != 0);
  REQUIRE(HostsDomain::wait_for([&] { return samples_flow(domain); }));

  domain.hosts().set_link(HostsDomain::host_of_node(consumer_node), false);
  REQUIRE(HostsDomain::wait_for([&] {
    const auto listed =
        domain.cli(1, {"--timeout-ms", "2000", "ls", "apps"}, HostsDomain::over_dds());
    const auto json = listed.json();
    return listed.rc == 0 && !json.is_discarded() && json.at("applications").size() == 1 &&
           json.at("applications")[0].value("unreachable", Json::array()) ==
               Json::array({"Consumer_1"});
  }));
  const auto released = domain.cli(1, {"release", "ProducerConsumer"}, HostsDomain::over_dds());
  INFO(released.out << released.err);
  CHECK(released.rc == 0);
  // Its node could not be asked: the process runs on behind the pulled cable.
  CHECK(::kill(consumer, 0) == 0);

  domain.hosts().set_link(HostsDomain::host_of_node(consumer_node), true);
  // Back: the node is asked what it runs, and the process that runs for nobody is ended.
  CHECK(HostsDomain::wait_for([&] {
    return std::none_of(pids.begin(), pids.end(), [](pid_t pid) { return ::kill(pid, 0) == 0; });
  }));
}
