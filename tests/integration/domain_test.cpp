// The whole product with real processes: rsca-domaind and two rsca-noded on loopback, on a DDS
// domain of their own, driven through the CLI and the control plane. Each test checks that what
// it launched leaves nothing behind: no component process, no allocation, no application.
// This file: a whole lifecycle, runtime models, admission and the domain's events;
// domain_launch_failure_test.cpp: launches that fail or are cancelled;
// domain_node_failure_test.cpp: daemons and components that die or stop.
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "domain_fixture.hpp"
#include "qos_checks.hpp"

using namespace rsca::test;
using namespace std::chrono_literals;
using rsca::control::Json;

namespace {

// The nice value of a process's main thread (/proc/PID/stat, the 19th field).
int nice_of(long pid) {
  std::ifstream stat(fmt::format("/proc/{}/stat", pid));
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  std::istringstream fields(text.substr(text.rfind(')') + 2)); // after the command name
  std::string field;
  for (int i = 3; i <= 19 && fields >> field; ++i) {
  }
  return std::stoi(field);
}

} // namespace

TEST_CASE("ProducerConsumer: install, launch, data flows, configure, query, stop, release",
          "[integration][domain]") {
  TestDomain domain;
  const Json app = domain.launch_shipped("ProducerConsumer");
  CHECK(app.at("state") == "running");
  REQUIRE(app.at("components").size() == 2);
  const auto pids = pids_of(app);
  for (long pid : pids)
    CHECK(process_exists(pid));

  // Producer_1 is periodic (20 ms): admission gave it a CPU and a priority, and its process runs
  // on that CPU only.
  for (const auto &c : app.at("components")) {
    if (c.at("id") != "Producer_1")
      continue;
    REQUIRE(c.contains("schedule"));
    const auto &schedule = c.at("schedule");
    CHECK(schedule.at("period_ns") == 20000000);
    CHECK(schedule.at("priority") == 10); // as the SAD gives it
    std::ifstream status(fmt::format("/proc/{}/status", c.at("pid").get<long>()));
    std::string line, allowed;
    while (std::getline(status, line))
      if (line.rfind("Cpus_allowed_list:", 0) == 0)
        allowed = line.substr(line.find_first_not_of(" \t", 18));
    CHECK(allowed == std::to_string(schedule.at("cpu").get<int>()));
  }
  // The node daemons run above the components they start when they may raise their priority;
  // the components run at the priority the nodes were started with (this test's).
  const int ours = getpriority(PRIO_PROCESS, 0);
  CHECK(nice_of(domain.node_pid(1)) <= ours);
  CHECK(nice_of(domain.node_pid(2)) <= ours);
  for (long pid : pids)
    CHECK(nice_of(pid) == ours);

  // Data flows across the connection: the consumer's count grows.
  CHECK(TestDomain::wait_for([&] { return received(domain, "ProducerConsumer") > 20; }));

  // Configure and query, typed against the PRF.
  auto [crc, cout_text] = domain.cli({"configure", "ProducerConsumer/Producer_1", "rate_hz=200"});
  INFO(cout_text);
  CHECK(crc == 0);
  auto q = domain.call(
      "app.query",
      Json{{"app", "ProducerConsumer"}, {"component", "Producer_1"}, {"ids", {"rate_hz"}}});
  REQUIRE(q.has_value());
  CHECK(q->at("properties").at("rate_hz").get<double>() == 200.0);
  auto [brc, bad] = domain.cli({"configure", "ProducerConsumer/Producer_1", "rate_hz=fast"});
  CHECK(brc == 1);
  CHECK_THAT(bad, Catch::Contains("\"fast\" is not a valid double"));
  q = domain.call(
      "app.query",
      Json{{"app", "ProducerConsumer"}, {"component", "Producer_1"}, {"ids", {"rate_hz"}}});
  CHECK(q->at("properties").at("rate_hz").get<double>() == 200.0); // nothing applied

  // Stop, start, release.
  REQUIRE(domain.call("app.stop", Json{{"app", "ProducerConsumer"}}).has_value());
  REQUIRE(domain.call("app.start", Json{{"app", "ProducerConsumer"}}).has_value());
  // Every component confirms its own release: its last reply is delivered before it exits.
  auto [rrc, rout] = domain.cli({"--json", "release", "ProducerConsumer"});
  INFO(rout);
  REQUIRE(rrc == 0);
  CHECK(Json::parse(rout).at("unconfirmed").empty());
  domain.require_clean(pids);
}

TEST_CASE("a GPP that does not pin admitted components leaves a periodic process free on every "
          "CPU, its schedule still admitted",
          "[integration][domain]") {
  TestDomain domain({kTestSdr / "dev/nodes/free1/DeviceManager.dcd.xml"});
  const Json app = domain.launch_shipped("ProducerConsumer");
  const auto pids = pids_of(app);
  std::string every_cpu;
  {
    std::ifstream status("/proc/self/status"); // this test may run on every CPU of the host
    std::string line;
    while (std::getline(status, line))
      if (line.rfind("Cpus_allowed_list:", 0) == 0)
        every_cpu = line.substr(line.find_first_not_of(" \t", 18));
  }
  for (const auto &c : app.at("components")) {
    if (c.at("id") != "Producer_1")
      continue;
    REQUIRE(c.contains("schedule")); // admitted as on any GPP
    std::ifstream status(fmt::format("/proc/{}/status", c.at("pid").get<long>()));
    std::string line, allowed;
    while (std::getline(status, line))
      if (line.rfind("Cpus_allowed_list:", 0) == 0)
        allowed = line.substr(line.find_first_not_of(" \t", 18));
    CHECK(allowed == every_cpu);
  }
  CHECK(TestDomain::wait_for([&] { return received(domain, "ProducerConsumer") > 20; }));
  REQUIRE(domain.call("app.release", Json{{"app", "ProducerConsumer"}}).has_value());
  domain.require_clean(pids);
}

TEST_CASE("install writes each component's runtime model, and its process starts from it",
          "[integration][domain]") {
  TestDomain domain;
  // Producer_1's package in APP: as a process of its own, or hosted in a component host.
  const auto [app, package] = GENERATE(std::pair{"ProducerConsumer", "Producer"},
                                       std::pair{"ProducerConsumerHosted", "ProducerLib"});
  INFO(app);
  const fs::path sad =
      kSource / fmt::format("profiles/dom/waveforms/{0}/{0}.sad.xml", std::string(app));
  auto [rc, out] = domain.cli({"install", sad.string()});
  INFO(out);
  REQUIRE(rc == 0);
  const fs::path model = domain.run_dir() / "repository/applications" / app /
                         fmt::format("dom/components/{0}/{0}.spd.xml.model.json", package);
  REQUIRE(fs::exists(model));
  // A default changed in the model only (its sources untouched): the launched component has it,
  // so its process read the model, not the XML.
  Json edited = Json::parse(std::ifstream(model));
  for (auto &d : edited["properties"]["definitions"])
    if (d["id"] == "message")
      d["value"] = "from the model";
  std::ofstream(model) << edited.dump();

  auto [lrc, lout] = domain.cli({"launch", app});
  INFO(lout);
  REQUIRE(lrc == 0);
  auto q = domain.call("app.query",
                       Json{{"app", app}, {"component", "Producer_1"}, {"ids", {"message"}}});
  REQUIRE(q.has_value());
  CHECK(q->at("properties").at("message") == "from the model");
  auto shown = domain.call("app.show", Json{{"app", app}});
  REQUIRE(shown.has_value());
  const auto pids = pids_of(*shown);
  REQUIRE(domain.call("app.release", Json{{"app", app}}).has_value());
  domain.require_clean(pids);
}

TEST_CASE("admission: launches fill the domain, the next is rejected with the reason, a release "
          "makes room again",
          "[integration][domain][allocator]") {
  // Two nodes whose GPPs offer one CPU each; each Greedy takes 60% of one.
  TestDomain domain({kTestSdr / "dev/nodes/small1/DeviceManager.dcd.xml",
                     kTestSdr / "dev/nodes/small2/DeviceManager.dcd.xml"});
  domain.install("Greedy");
  std::vector<long> pids;
  for (const char *name : {"g1", "g2"}) {
    auto app = domain.call("app.create", Json{{"application", "Greedy"}, {"name", name}});
    INFO((app ? std::string() : app.error().message));
    REQUIRE(app.has_value());
    for (long pid : pids_of(*app))
      pids.push_back(pid);
  }
  // Spread over both nodes by necessity: each GPP holds one.
  auto devices = domain.call("domain.devices");
  REQUIRE(devices.has_value());
  for (const auto &d : devices->at("devices"))
    CHECK(d.at("capacity").at("cpu_capacity").at("allocated").get<double>() == Approx(60.0));

  // The third is rejected before anything runs, and says why on each device.
  auto [rc, out] = domain.cli({"launch", "Greedy", "--name", "g3"});
  INFO(out);
  CHECK(rc == 5);
  CHECK_THAT(out,
             Catch::Contains("small1:GPP_1 (cpp): cpu_capacity needs 60.0% CPU, 40.0% CPU free"));
  CHECK_THAT(out,
             Catch::Contains("small2:GPP_1 (cpp): cpu_capacity needs 60.0% CPU, 40.0% CPU free"));
  auto plan = domain.call("app.plan", Json{{"application", "Greedy"}});
  REQUIRE(plan.has_value());
  CHECK(plan->at("admitted") == false);

  // Nothing was reserved by the rejection: a release makes room for exactly one more.
  REQUIRE(domain.call("app.release", Json{{"app", "g1"}}).has_value());
  auto again = domain.call("app.create", Json{{"application", "Greedy"}, {"name", "g3"}});
  INFO((again ? std::string() : again.error().message));
  REQUIRE(again.has_value());
  for (long pid : pids_of(*again))
    pids.push_back(pid);
  REQUIRE(domain.call("app.release", Json{{"app", "g2"}}).has_value());
  REQUIRE(domain.call("app.release", Json{{"app", "g3"}}).has_value());
  domain.require_clean(pids);
}

TEST_CASE("the domain publishes what happens to it, and rsca events follows it",
          "[integration][domain][events]") {
  TestDomain domain;
  domain.install("Healthy");
  auto app = domain.call("app.create", Json{{"application", "Healthy"}});
  REQUIRE(app.has_value());
  REQUIRE(domain.call("app.release", Json{{"app", "Healthy"}}).has_value());
  domain.kill_node(2);
  // A follower that starts now still gets the recent events, in order, one JSON object a line.
  auto [rc, out] = domain.cli({"--json", "events", "--count", "5", "--wait-ms", "10000"});
  INFO(out);
  REQUIRE(rc == 0);
  std::vector<std::string> kinds;
  std::istringstream lines(out);
  for (std::string line; std::getline(lines, line);) {
    const Json event = Json::parse(line);
    kinds.push_back(event.at("kind"));
    if (event.at("kind") == "application.created")
      CHECK(event.at("details").at("application") == "Healthy");
    if (event.at("kind") == "node.removed")
      CHECK(event.at("details").at("node") == "node2");
  }
  CHECK(kinds == std::vector<std::string>{"node.added", "node.added", "application.created",
                                          "application.released", "node.removed"});
  domain.require_clean(pids_of(*app));
}

TEST_CASE("a deadline the writer stops meeting is reported as a domain event",
          "[integration][domain][events]") {
  // Over DDS between two processes, and in-host between two components of one component host.
  const std::string name =
      GENERATE(as<std::string>{}, "ProducerConsumer", "ProducerConsumerHosted");
  INFO(name);
  TestDomain domain;
  auto [rc, out] = domain.cli(
      {"launch", (kSource / "profiles/dom/waveforms" / name / (name + ".sad.xml")).string()});
  REQUIRE(rc == 0);
  auto app = domain.call("app.show", Json{{"app", name}});
  REQUIRE(app.has_value());
  // The connection asks for a sample every 100 ms at least; at 2 Hz the producer misses it.
  REQUIRE(domain.cli({"configure", name + "/Producer_1", "rate_hz=2"}).first == 0);
  const Json problem = connection_problem(domain, "deadline missed");
  INFO(problem.dump());
  REQUIRE_FALSE(problem.is_null());
  CHECK(problem.value("application", "") == name);
  CHECK(problem.value("component", "") == "Consumer_1");
  CHECK(problem.value("connection", "") == "samples");
  CHECK(problem.value("problem", "") == "deadline missed");
  CHECK(problem.value("count", 0) > 0);
  // Both ends count the misses in the connection's live state.
  auto list = domain.call("connection.list", Json{{"app", name}});
  REQUIRE(list.has_value());
  const Json &samples = list->at("connections")[0];
  CHECK(samples.at("uses_state").at("deadline_missed").get<int>() > 0);
  CHECK(samples.at("provides_state").at("deadline_missed").get<int>() > 0);
  CHECK(samples.at("provides_state").at("in_host") == (name == "ProducerConsumerHosted"));
  REQUIRE(domain.call("app.release", Json{{"app", name}}).has_value());
  domain.require_clean(pids_of(*app));
}

TEST_CASE("a writer that stops asserting its liveliness is reported as a domain event",
          "[integration][domain][events]") {
  // The connection asks the producer's writer to be alive every 300 ms. A frozen process (here
  // SIGSTOP; in life a hung one) has not exited, so only the connection's liveliness tells.
  // Both components on one node (the node's ring: the writer's process asserts it) or on two
  // (the writer's node asserts it on DDS for it while the process does, the reader's node
  // counts what DDS says into its ring).
  // A writer that dies (SIGKILL) loses its liveliness too, as a DDS writer's would: on its own
  // node at once (the node sees the process end), from another node when the lease passes since
  // its node last said it was alive (the relay's writer goes with it).
  const std::string strategy = GENERATE(as<std::string>{}, "pack", "spread");
  const int signal = GENERATE(SIGSTOP, SIGKILL);
  INFO("placement " << strategy << ", signal " << signal);
  TestDomain domain;
  domain.install("Lively");
  auto [rc, out] = domain.cli({"launch", "Lively", "--strategy", strategy});
  INFO(out);
  REQUIRE(rc == 0);
  auto app = domain.call("app.show", Json{{"app", "Lively"}});
  REQUIRE(app.has_value());
  auto listed = domain.call("connection.list", Json{{"app", "Lively"}});
  REQUIRE(listed.has_value());
  // Through the node's ring either way; relayed by the two nodes when spread.
  const Json state = listed->at("connections").at(0).at("provides_state");
  CHECK(state.value("same_host", false));
  CHECK(state.value("relayed", false) == (strategy == "spread"));
  const long producer = pid_of(*app, "Producer_1");
  REQUIRE(producer > 0);
  REQUIRE(::kill(static_cast<pid_t>(producer), signal) == 0);
  const Json problem = connection_problem(domain, "liveliness lost");
  if (signal == SIGSTOP)
    ::kill(static_cast<pid_t>(producer), SIGCONT);
  INFO(problem.dump());
  REQUIRE_FALSE(problem.is_null());
  CHECK(problem.value("application", "") == "Lively");
  CHECK(problem.value("component", "") == "Consumer_1");
  CHECK(problem.value("connection", "") == "samples");
  CHECK(problem.value("count", 0) > 0);
  REQUIRE(domain.call("app.release", Json{{"app", "Lively"}}).has_value());
  domain.require_clean(pids_of(*app));
}
