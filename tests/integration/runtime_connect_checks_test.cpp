// rsca connect against a real domain (issue 18, defect 11): --qos takes the SAD's QoS names and
// values, and an end that can never exist is refused at once, with a bounded message, and never
// kept pending.
#include "domain_fixture.hpp"

using namespace rsca::test;

namespace {

// The runtime connections `rsca --json ls connections` lists.
std::vector<Json> listed_runtime_connections(TestDomain &domain) {
  auto [rc, out] = domain.cli({"--json", "ls", "connections"});
  INFO(out);
  REQUIRE(rc == 0);
  const Json listed = Json::parse(out);
  std::vector<Json> runtime;
  for (const auto &c : listed.at("connections"))
    if (c.at("application") == "(runtime)")
      runtime.push_back(c);
  return runtime;
}

} // namespace

TEST_CASE("rsca connect --qos takes the QoS names and values a SAD connection takes, and both "
          "live ends apply them",
          "[integration][connections]") {
  TestDomain domain(1);
  // Neither application runs: the connection is pending, and listed with its QoS.
  auto [rc, out] =
      domain.cli({"connect", "a/Producer_1.samples_out", "b/Consumer_1.samples_in", "--id",
                  "sad_qos", "--qos", "deadline=100ms", "--qos", "lease=1.5s", "--qos",
                  "liveliness=manualbytopic", "--qos", "transportpriority=-2"});
  INFO(out);
  REQUIRE(rc == 0);
  const auto listed = listed_runtime_connections(domain);
  REQUIRE(listed.size() == 1);
  const Json &qos = listed.at(0).at("qos");
  CHECK(listed.at(0).at("id") == "sad_qos");
  CHECK(qos.at("deadline_ns") == 100'000'000);
  CHECK(qos.at("lease_ns") == 1'500'000'000);
  CHECK(qos.at("liveliness") == "manualbytopic");
  CHECK(qos.at("transportpriority") == -2);

  // Once both ends run, each applies them, as its live transport reads them back (the ring of
  // the node by default; DDS's own reader and writer on direct DDS).
  const std::string transport = GENERATE(as<std::string>{}, "", "direct");
  INFO("transport " << (transport.empty() ? "by default" : transport));
  if (!transport.empty()) {
    REQUIRE(domain.cli({"disconnect", "sad_qos"}).first == 0);
    REQUIRE(domain
                .cli({"connect", "a/Producer_1.samples_out", "b/Consumer_1.samples_in", "--id",
                      "sad_qos", "--qos", "deadline=100ms", "--qos", "lease=1.5s", "--qos",
                      "liveliness=manualbytopic", "--qos", "transport=" + transport})
                .first == 0);
  }
  std::vector<long> pids;
  for (const auto &[sad, name] : {std::pair{"QosSource", "a"}, std::pair{"QosSink", "b"}}) {
    domain.install(sad);
    REQUIRE(domain.cli({"launch", sad, "--name", name}).first == 0);
    for (long pid : pids_of(domain.call("app.show", Json{{"app", name}}).value()))
      pids.push_back(pid);
  }
  Json live;
  REQUIRE(TestDomain::wait_for([&] {
    live = listed_runtime_connections(domain).at(0);
    return live.at("uses_state").contains("qos") && live.at("provides_state").contains("qos");
  }));
  INFO(live.dump());
  for (const char *end : {"uses_state", "provides_state"}) {
    const Json &applied = live.at(end).at("qos");
    INFO(end);
    CHECK(applied.at("deadline_ns") == 100'000'000);
    CHECK(applied.at("lease_ns") == 1'500'000'000);
    CHECK(applied.at("liveliness") == "manualbytopic");
  }
  CHECK(live.at("provides_state").at("same_host") == transport.empty());
  REQUIRE(domain.cli({"disconnect", "sad_qos"}).first == 0);
  REQUIRE(domain.call("app.release", Json{{"app", "a"}}).has_value());
  REQUIRE(domain.call("app.release", Json{{"app", "b"}}).has_value());

  // A value the SAD refuses is refused the same way (no unit), and nothing is kept.
  auto [brc, bout] = domain.cli({"connect", "a/Producer_1.samples_out", "b/Consumer_1.samples_in",
                                 "--id", "no_unit", "--qos", "deadline=100"});
  INFO(bout);
  CHECK(brc == 1);
  CHECK_THAT(bout, Catch::Contains("\"deadline\" is 100, not a duration such as 100ms"));
  CHECK(listed_runtime_connections(domain).empty());
  domain.require_clean(pids);
}

TEST_CASE("rsca connect refuses an end that can never exist at once, quoting an excerpt",
          "[integration][connections]") {
  TestDomain domain(1);
  const std::string huge(100 * 1024, 'n');
  struct Case {
    std::vector<std::string> args;
    std::string says;
  };
  const std::vector<Case> cases{
      {{"a/b/c.d", "x/Consumer_1.samples_in"},
       "uses end: the component \"b/c\" is not a name: it holds a '/'"},
      {{"a/Producer_1.samples_out", huge + "/Consumer_1.samples_in"},
       "provides end: the application \"nnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnn... (102400 "
       "bytes)\" "
       "is too long a name: at most 255 bytes"},
      {{"a/Producer_1.samples_out", "b/Consumer_1." + huge},
       "provides end: the port \"nnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnnn... (102400 bytes)\""},
      {{"a/Producer\x01_1.samples_out", "b/Consumer_1.samples_in"},
       "uses end: the component \"Producer\\x01_1\" is not a name: it holds a control character"},
      {{"node1:.samples_out", "b/Consumer_1.samples_in"}, "uses end: the device has no name"},
      {{"a/Producer_1.samples_out", "b/Consumer_1.samples_in", "--id", "x/y"},
       "the connection id \"x/y\" is not a name"},
  };
  for (const auto &c : cases) {
    std::vector<std::string> args{"connect"};
    args.insert(args.end(), c.args.begin(), c.args.end());
    auto [rc, out] = domain.cli(args);
    INFO(out.substr(0, 2000));
    CHECK(rc == 1); // a bad request
    CHECK_THAT(out, Catch::Contains(c.says));
    CHECK(out.size() < 1000); // the message quotes an excerpt, not the name
  }
  CHECK(listed_runtime_connections(domain).empty());
}
