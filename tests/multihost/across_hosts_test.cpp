// A domain across network hosts (network namespaces joined by a bridge): the domain daemon and
// each node daemon on a host of its own, DDS between them over a real network interface.
#include <catch2/catch.hpp>

#include <algorithm>
#include <csignal>
#include <set>

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
bool samples_flow(HostsDomain &domain) {
  const auto c = connection_state(domain, "ProducerConsumer", "samples");
  if (c.is_null() || !c.contains("provides_state"))
    return false;
  const auto &provides = c.at("provides_state");
  return provides.at("matched") == 1 && provides.at("samples").get<int>() > 0;
}

} // namespace

TEST_CASE("ProducerConsumer spread over two network hosts: launched, matched, its data on the wire",
          "[multihost]") {
  HostsDomain domain(2);
  const int consumer_host = HostsDomain::host_of_node(2);
  const auto received_before = domain.hosts().received_bytes(consumer_host);

  // The CLI on the domain's host, over DDS: nothing of it shares a host with a node.
  const auto launched =
      domain.cli(1, {"launch", kProducerConsumer, "--strategy", "spread"}, HostsDomain::over_dds());
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

  REQUIRE(HostsDomain::wait_for([&] { return samples_flow(domain); }));
  // The samples crossed the consumer host's network interface, not a loopback.
  CHECK(domain.hosts().received_bytes(consumer_host) > received_before);

  const auto released = domain.cli(1, {"release", "ProducerConsumer"}, HostsDomain::over_dds());
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
