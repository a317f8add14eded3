// What the QoS tests read of a live domain: a component's property, a connection's live ends as
// `rsca --json ls connections` lists them, and the connection problems the domain reports.
#pragma once

#include <sstream>

#include "domain_fixture.hpp"

namespace rsca::test {

// A property of `component` of `app` (a number); -1 when the query fails.
inline long property(TestDomain &domain, const std::string &app, const std::string &component,
                     const std::string &id) {
  auto q = domain.call("app.query", Json{{"app", app}, {"component", component}, {"ids", {id}}});
  return q ? q->at("properties").at(id).get<long>() : -1;
}

// Connection `id` as `rsca --json ls connections` lists it; null when it does not.
inline Json listed_connection(TestDomain &domain, const std::string &id) {
  auto [rc, out] = domain.cli({"--json", "ls", "connections"});
  INFO(out);
  REQUIRE(rc == 0);
  const Json listed = Json::parse(out);
  for (const auto &c : listed.at("connections"))
    if (c.at("id") == id)
      return c;
  return nullptr;
}

// A number from one end's live state of connection `id`; -1 while that end shows none.
inline long end_value(TestDomain &domain, const std::string &id, const char *end, const char *key) {
  const Json c = listed_connection(domain, id);
  if (c.is_null() || c.at(end).is_null() || !c.at(end).contains(key))
    return -1;
  return c.at(end).at(key).get<long>();
}

inline std::string node_of(TestDomain &domain, const std::string &app) {
  auto shown = domain.call("app.show", Json{{"app", app}});
  REQUIRE(shown.has_value());
  return shown->at("components").at(0).at("node").get<std::string>();
}

// The details of the last "connection.problem" event of kind `problem` (of connection
// `connection`, when one is named) the domain reported, waited for; null when none came.
inline Json connection_problem(TestDomain &domain, const std::string &problem,
                               const std::string &connection = {}) {
  Json found;
  TestDomain::wait_for([&] {
    auto [rc, events] = domain.cli({"--json", "events", "--wait-ms", "300"});
    std::istringstream lines(events);
    for (std::string line; std::getline(lines, line);) {
      const Json event = Json::parse(line, nullptr, false);
      if (!event.is_discarded() && event.value("kind", "") == "connection.problem" &&
          event.at("details").value("problem", "") == problem &&
          (connection.empty() || event.at("details").value("connection", "") == connection))
        found = event.at("details");
    }
    return !found.is_null();
  });
  return found;
}

// A way to carry a connection: the transport named, and the nodes its two ends are spread over
// (the nodes' relay when two carry transport "node").
struct Way {
  const char *name;
  const char *transport;
  int nodes;
};
inline const Way kRing{"the ring of one node", "node", 1};
inline const Way kRelay{"the relay between two nodes", "node", 2};
inline const Way kTcp{"a TCP stream", "tcp", 1};
inline const Way kDirect{"direct DDS", "direct", 1};

// QosSource's producer (500 Hz) and QosSink's consumer, each an application of its own (on its
// own node when the way takes two), connected as runtime connection "c" on `way` with `qos`
// ("depth=5"); delivering when made.
class QosPair {
public:
  QosPair(const Way &way, const std::vector<std::string> &qos) : domain(way.nodes) {
    launch("QosSource", {});
    launch("QosSink", way.nodes > 1 ? std::vector<std::string>{"--strategy", "spread"}
                                    : std::vector<std::string>{});
    if (way.nodes > 1)
      REQUIRE(node_of(domain, "QosSink") != node_of(domain, "QosSource"));
    std::vector<std::string> args{"connect",
                                  "QosSource/Producer_1.samples_out",
                                  "QosSink/Consumer_1.samples_in",
                                  "--id",
                                  "c",
                                  "--qos",
                                  std::string("transport=") + way.transport};
    for (const auto &q : qos)
      args.insert(args.end(), {"--qos", q});
    auto [rc, out] = domain.cli(args);
    INFO(out);
    REQUIRE(rc == 0);
    REQUIRE(TestDomain::wait_for([&] { return consumer("received") > 20; }));
  }

  long producer(const char *id) { return property(domain, "QosSource", "Producer_1", id); }
  long consumer(const char *id) { return property(domain, "QosSink", "Consumer_1", id); }
  pid_t producer_pid() const { return static_cast<pid_t>(pids.at(0)); }
  pid_t consumer_pid() const { return static_cast<pid_t>(pids.at(1)); }
  Json connection() { return listed_connection(domain, "c"); }

  // Disconnects and releases both applications; the test then requires them clean.
  void release() {
    REQUIRE(domain.cli({"disconnect", "c"}).first == 0);
    REQUIRE(domain.call("app.release", Json{{"app", "QosSink"}}).has_value());
    REQUIRE(domain.call("app.release", Json{{"app", "QosSource"}}).has_value());
  }

  TestDomain domain;
  std::vector<long> pids; // the producer's, then the consumer's

private:
  void launch(const std::string &app, const std::vector<std::string> &options) {
    domain.install(app);
    std::vector<std::string> args{"launch", app};
    args.insert(args.end(), options.begin(), options.end());
    auto [rc, out] = domain.cli(args);
    INFO(out);
    REQUIRE(rc == 0);
    auto shown = domain.call("app.show", Json{{"app", app}});
    REQUIRE(shown.has_value());
    pids.push_back(shown->at("components").at(0).at("pid").get<long>());
  }
};

} // namespace rsca::test
