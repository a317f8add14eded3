// The QoS of a connection through the nodes' relays across two network hosts (issue 38): every
// sample delivered once and in order, the deadline met with no miss, a stopped keep-last reader
// given only the newest at its start, and a frozen writer's lost liveliness reported by the
// reader's end, on a real network interface between the hosts (network namespaces joined by a
// bridge).
#include <catch2/catch.hpp>

#include <algorithm>
#include <csignal>
#include <sstream>

#include "hosts_domain.hpp"

using namespace rsca::test;

namespace {

const fs::path kQosSdr = kSource / "tests/data/integration/dom/waveforms";

// A number property of `target` (APP or APP/COMPONENT) as `rsca query` reads it; -1 when it
// cannot.
long queried(HostsDomain &domain, const std::string &target, const std::string &id) {
  const auto run = domain.cli(1, {"query", target, id}, HostsDomain::over_dds());
  const auto json = run.json();
  if (run.rc != 0 || json.is_discarded())
    return -1;
  const Json &values = json.contains("properties") ? json.at("properties") : json;
  return values.contains(id) && values.at(id).is_number() ? values.at(id).get<long>() : -1;
}

// The live state of runtime connection `id`'s end `end`, or null.
Json end_state(HostsDomain &domain, const std::string &id, const char *end) {
  const auto listed = domain.cli(1, {"ls", "connections"}, HostsDomain::over_dds());
  const auto json = listed.json();
  if (listed.rc != 0 || json.is_discarded())
    return nullptr;
  for (const auto &c : json.at("connections"))
    if (c.at("id") == id)
      return c.at(end);
  return nullptr;
}

// QosSource and QosSink launched on two hosts (the sink spread away from the source); their
// component pids.
std::vector<pid_t> launch_on_two_hosts(HostsDomain &domain) {
  std::vector<pid_t> pids;
  std::vector<std::string> nodes;
  for (const auto &[app, options] :
       {std::pair{"QosSource", std::vector<std::string>{}},
        std::pair{"QosSink", std::vector<std::string>{"--strategy", "spread"}}}) {
    std::vector<std::string> args{"launch",
                                  (kQosSdr / app / (std::string(app) + ".sad.xml")).string()};
    args.insert(args.end(), options.begin(), options.end());
    const auto launched = domain.cli(1, args, HostsDomain::over_dds());
    INFO(launched.out << launched.err);
    REQUIRE(launched.rc == 0);
    const auto c = launched.json().at("components").at(0);
    pids.push_back(c.at("pid").get<pid_t>());
    nodes.push_back(c.at("node").get<std::string>());
  }
  REQUIRE(nodes.at(0) != nodes.at(1)); // two hosts
  return pids;
}

// Connection `id` from the source to the sink with these `--qos` settings.
void connect_across(HostsDomain &domain, const std::string &id,
                    const std::vector<std::string> &qos) {
  std::vector<std::string> args{"connect", "QosSource/Producer_1.samples_out",
                                "QosSink/Consumer_1.samples_in", "--id", id};
  for (const auto &q : qos) {
    args.emplace_back("--qos");
    args.push_back(q);
  }
  const auto connected = domain.cli(1, args, HostsDomain::over_dds());
  INFO(connected.out << connected.err);
  REQUIRE(connected.rc == 0);
}

// The sink's consumer reaches sequence `last` with no sequence missing or repeated on the way.
void received_in_order_up_to(HostsDomain &domain, long last) {
  CHECK(HostsDomain::wait_for(
      [&] { return queried(domain, "QosSink/Consumer_1", "last_sequence") == last; }));
  CHECK(queried(domain, "QosSink/Consumer_1", "sequence_gaps") == 0);
  CHECK(queried(domain, "QosSink/Consumer_1", "sequence_repeats") == 0);
}

// Disconnects `id`, releases both applications, and waits for their processes to be gone.
void release_both(HostsDomain &domain, const std::string &id, const std::vector<pid_t> &pids) {
  CHECK(domain.cli(1, {"disconnect", id}, HostsDomain::over_dds()).rc == 0);
  for (const char *app : {"QosSink", "QosSource"})
    CHECK(domain.cli(1, {"release", app}, HostsDomain::over_dds()).rc == 0);
  const auto apps = domain.cli(1, {"ls", "apps"});
  REQUIRE(apps.rc == 0);
  CHECK(apps.json().at("applications").empty());
  CHECK(HostsDomain::wait_for([&] {
    return std::none_of(pids.begin(), pids.end(), [](pid_t pid) { return ::kill(pid, 0) == 0; });
  }));
}

// The details of the first "connection.problem" event saying `problem`, waited for; null when
// none came in time.
Json connection_problem(HostsDomain &domain, const std::string &problem) {
  Json found;
  HostsDomain::wait_for([&] {
    const auto run = domain.cli(1, {"events", "--wait-ms", "300"}, HostsDomain::over_dds());
    std::istringstream lines(run.out);
    for (std::string line; found.is_null() && std::getline(lines, line);) {
      const Json event = Json::parse(line, nullptr, false);
      if (!event.is_discarded() && event.value("kind", "") == "connection.problem" &&
          event.at("details").value("problem", "") == problem)
        found = event.at("details");
    }
    return !found.is_null();
  });
  return found;
}

// A process stopped with SIGSTOP for as long as it lives, continued however the test ends.
class Frozen {
public:
  explicit Frozen(pid_t pid) : pid_(pid) { ::kill(pid_, SIGSTOP); }
  ~Frozen() { resume(); }
  Frozen(const Frozen &) = delete;
  Frozen &operator=(const Frozen &) = delete;
  void resume() { ::kill(pid_, SIGCONT); }

private:
  pid_t pid_;
};

} // namespace

TEST_CASE("a reliable connection with a deadline through the relays across two hosts delivers "
          "every sample once and in order and misses no deadline",
          "[multihost]") {
  HostsDomain domain(2);
  const auto pids = launch_on_two_hosts(domain);
  connect_across(domain, "c",
                 {"reliability=reliable", "history=keeplast", "depth=1000", "deadline=100ms"});

  // 500 Hz: 1000 samples are 2 s, twenty deadline periods.
  REQUIRE(
      HostsDomain::wait_for([&] { return queried(domain, "QosSink", "received") >= 1000; }, 30s));
  const Json provides = end_state(domain, "c", "provides_state");
  INFO(provides.dump());
  REQUIRE_FALSE(provides.is_null());
  CHECK(provides.at("relayed") == true);
  CHECK(provides.at("qos").at("deadline_ns") == 100'000'000);
  CHECK(provides.at("deadline_missed") == 0);
  CHECK(end_state(domain, "c", "uses_state").at("deadline_missed") == 0);

  const auto stopped = domain.cli(1, {"stop", "QosSource"}, HostsDomain::over_dds());
  REQUIRE(stopped.rc == 0);
  received_in_order_up_to(domain, queried(domain, "QosSource/Producer_1", "last_sequence"));
  release_both(domain, "c", pids);
}

TEST_CASE("a keep-last reader whose component is stopped gets, once started, at most depth of "
          "the samples written meanwhile, the newest, through the relays across two hosts",
          "[multihost]") {
  constexpr long kDepth = 5;
  HostsDomain domain(2);
  const auto pids = launch_on_two_hosts(domain);
  connect_across(domain, "c", {"reliability=reliable", "history=keeplast", "depth=5"});
  {
    const Json provides = end_state(domain, "c", "provides_state");
    INFO(provides.dump());
    REQUIRE_FALSE(provides.is_null());
    CHECK(provides.at("relayed") == true);
    CHECK(provides.at("qos").at("depth") == kDepth);
  }
  REQUIRE(domain.cli(1, {"stop", "QosSink"}, HostsDomain::over_dds()).rc == 0);
  const long before = queried(domain, "QosSource/Producer_1", "last_sequence");
  REQUIRE(HostsDomain::wait_for([&] {
    return queried(domain, "QosSource/Producer_1", "last_sequence") >= before + 20 * kDepth;
  }));
  REQUIRE(domain.cli(1, {"stop", "QosSource"}, HostsDomain::over_dds()).rc == 0);
  const long last = queried(domain, "QosSource/Producer_1", "last_sequence");
  REQUIRE(domain.cli(1, {"start", "QosSink"}, HostsDomain::over_dds()).rc == 0);

  // The consumer counts from its start: what it got are the newest, none missing up to the last.
  received_in_order_up_to(domain, last);
  const long got = queried(domain, "QosSink/Consumer_1", "received");
  INFO("written while stopped " << last - before << ", received at the start " << got);
  CHECK(got >= 1);
  CHECK(got <= kDepth);
  release_both(domain, "c", pids);
}

TEST_CASE("a writer frozen past its liveliness lease is reported lost by the reader's end "
          "through the relays across two hosts, and delivers again once resumed",
          "[multihost]") {
  HostsDomain domain(2);
  const auto pids = launch_on_two_hosts(domain);
  connect_across(domain, "c", {"liveliness=automatic", "lease=300ms"});
  REQUIRE(HostsDomain::wait_for([&] { return queried(domain, "QosSink", "received") > 50; }, 30s));
  {
    const Json provides = end_state(domain, "c", "provides_state");
    INFO(provides.dump());
    REQUIRE_FALSE(provides.is_null());
    CHECK(provides.at("relayed") == true);
    CHECK(provides.at("qos").at("lease_ns") == 300'000'000);
  }
  Frozen frozen(pids.at(0)); // the producer
  const Json problem = connection_problem(domain, "liveliness lost");
  frozen.resume();
  INFO(problem.dump());
  REQUIRE_FALSE(problem.is_null());
  CHECK(problem.value("application", "") == "QosSink");
  CHECK(problem.value("component", "") == "Consumer_1");
  const long received = queried(domain, "QosSink/Consumer_1", "received");
  CHECK(HostsDomain::wait_for(
      [&] { return queried(domain, "QosSink/Consumer_1", "received") > received + 50; }));
  release_both(domain, "c", pids);
}
