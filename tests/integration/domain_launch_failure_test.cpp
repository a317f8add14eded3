// The whole product with real processes (domain_fixture.hpp), continued from domain_test.cpp:
// launches that fail (a missing executable, a component that crashes at start or never
// registers, a property of the wrong type, no device that matches) or are cancelled (the CLI
// stops waiting, Ctrl-C, a cancel that overtakes its launch) roll back and leave nothing behind.
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "domain_fixture.hpp"

using namespace rsca::test;
using namespace std::chrono_literals;
using rsca::control::Json;

TEST_CASE("a missing executable fails the launch at execute and rolls back",
          "[integration][domain][failure]") {
  TestDomain domain;
  domain.install("MissingExecutable");
  auto [rc, out] = domain.cli({"launch", "MissingExecutable"});
  CHECK(rc == 6);
  CHECK_THAT(out, Catch::Contains("failed at step 'execute'"));
  CHECK_THAT(out, Catch::Contains("rsca-no-such-program"));
  CHECK_THAT(out, Catch::Contains("rolled back"));
  domain.require_clean({});
  CHECK(domain.running_pids().empty());
}

TEST_CASE("a component crashing at start fails the launch and rolls back",
          "[integration][domain][failure]") {
  TestDomain domain;
  domain.install("CrashAtStart");
  auto [rc, out] = domain.cli({"launch", "CrashAtStart"});
  CHECK(rc != 0);
  CHECK_THAT(out, Catch::Contains("failed at step 'start'"));
  CHECK_THAT(out, Catch::Contains("Victim_1"));
  CHECK(TestDomain::wait_for([&] { return domain.running_pids().empty(); }));
  domain.require_clean({});
}

TEST_CASE("a component that never registers fails the launch at register",
          "[integration][domain][failure]") {
  TestDomain domain(2, /*registration_timeout_ms=*/1500);
  domain.install("NeverRegisters");
  auto [rc, out] = domain.cli({"launch", "NeverRegisters"});
  // The domain answered: a launch that failed and was rolled back (6), not an unreachable domain.
  CHECK(rc == 6);
  CHECK_THAT(out, Catch::Contains("failed at step 'register'"));
  CHECK_THAT(out, Catch::Contains("Victim_1"));
  domain.require_clean({});
  CHECK(domain.running_pids().empty());
}

TEST_CASE("a launch the CLI stops waiting for is cancelled and rolled back",
          "[integration][domain][failure]") {
  // The domain would wait a minute for the registration that never comes; only the cancel ends
  // the launch within wait_for's limit.
  TestDomain domain(2, /*registration_timeout_ms=*/60000);
  domain.install("NeverRegisters");
  // The CLI waits six of its 1 s timeouts, then cancels the launch. (Not shorter: the request
  // must reach the domain within the CLI's timeout on a loaded machine too.)
  auto [rc, out] = domain.cli({"--timeout-ms", "1000", "launch", "NeverRegisters"});
  CHECK(rc == 4); // a timeout
  CHECK_THAT(out, Catch::Contains("had not finished launching NeverRegisters after 6000 ms"));
  CHECK_THAT(out, Catch::Contains("the launch is cancelled"));
  CHECK_THAT(out, !Catch::Contains("rsca domain up"));
  CHECK(TestDomain::wait_for([&] { return domain.running_pids().empty(); }));
  // The cancel ends the launch at its step's end: under the sanitizers the launch may still be
  // fetching its code when the CLI gives up, and rolls back once that step has ended.
  CHECK(TestDomain::wait_for([&] {
    auto devices = domain.call("domain.devices");
    if (!devices)
      return false;
    for (const auto &d : devices->at("devices"))
      for (const auto &[name, c] : d.at("capacity").items())
        if (c.at("allocated").get<double>() > 1e-9)
          return false;
    return true;
  }));
  domain.require_clean({});
}

TEST_CASE("Ctrl-C on rsca launch cancels the launch, which rolls back",
          "[integration][domain][failure]") {
  TestDomain domain(2, /*registration_timeout_ms=*/60000);
  domain.install("NeverRegisters");
  const fs::path out = domain.run_dir() / "interrupted.out";
  // exec: the signal goes to rsca itself, not to a shell around it.
  ChildProcess cli("/bin/sh",
                   {"-c", "exec \"$0\" \"$@\" > " + out.string() + " 2>&1",
                    (kBin / "rsca").string(), "launch", "NeverRegisters"},
                   domain.env());
  // The launch is waiting for the registration that never comes once its process runs.
  REQUIRE(TestDomain::wait_for([&] { return !domain.running_pids().empty(); }));
  ::kill(cli.pid(), SIGINT);
  const auto status = cli.wait_exit(20s);
  std::ifstream in(out);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  INFO(text);
  REQUIRE(status.has_value());
  REQUIRE(WIFEXITED(*status));
  CHECK(WEXITSTATUS(*status) == 6); // failed, rolled back
  CHECK_THAT(text, Catch::Contains("interrupted; the launch is cancelled"));
  // "cancelled while N of M had registered", or "cancelled before this step" when the cancel
  // came while the second node was still starting its process.
  CHECK_THAT(text, Catch::Contains("failed at step 'register': cancelled"));
  CHECK_THAT(text, Catch::Contains("rolled back"));
  CHECK(TestDomain::wait_for([&] { return domain.running_pids().empty(); }));
  domain.require_clean({});
}

TEST_CASE("a cancel that overtakes its launch's request keeps the launch from beginning",
          "[integration][domain][failure]") {
  // The CLI's cancel and its create travel apart; a create that arrives after its cancel must
  // not launch an application its caller was told would not run.
  TestDomain domain(2);
  domain.install("Healthy");
  auto cancelled = domain.call("app.cancel", Json{{"launch_id", "overtaken-1"}});
  REQUIRE(cancelled.has_value());
  CHECK(cancelled->at("cancelled") == true);
  CHECK(cancelled->at("begun") == false);
  auto created =
      domain.call("app.create", Json{{"application", "Healthy"}, {"launch_id", "overtaken-1"}});
  REQUIRE_FALSE(created.has_value());
  CHECK_THAT(created.error().message, Catch::Contains("cancelled before it began"));
  CHECK(domain.running_pids().empty());
  domain.require_clean({});
  // The name was not kept: the next launch takes it.
  auto next = domain.call("app.create", Json{{"application", "Healthy"}, {"launch_id", "after-1"}});
  REQUIRE(next.has_value());
  CHECK(next->at("name") == "Healthy");
  REQUIRE(domain.call("app.release", Json{{"app", "Healthy"}}).has_value());
}

TEST_CASE("a property value of the wrong type is refused at install, before anything runs",
          "[integration][domain][failure]") {
  TestDomain domain;
  auto [rc, out] =
      domain.cli({"install", "--sdrroot", kTestSdr.string(),
                  (kTestSdr / "dom/waveforms/WrongValueType/WrongValueType.sad.xml").string()});
  CHECK(rc == 1);
  CHECK_THAT(out, Catch::Contains("WrongValueType.sad.xml:26:52"));
  CHECK_THAT(out, Catch::Contains("\"eleven\" is not a valid ulong"));
  auto installed = domain.call("domain.installed");
  REQUIRE(installed.has_value());
  CHECK(installed->at("applications").empty());
}

TEST_CASE("no device that matches: the launch is rejected with the reason per device",
          "[integration][domain][failure]") {
  TestDomain domain;
  domain.install("NoMatchingDevice");
  auto [rc, out] = domain.cli({"launch", "NoMatchingDevice"});
  CHECK(rc == 5);
  CHECK_THAT(out, Catch::Contains("failed at step 'allocate'"));
  CHECK_THAT(out, Catch::Contains(
                      "node1:GPP_1 (cpp): os_name is Linux, implementation cpp needs VxWorks"));
  CHECK_THAT(out, Catch::Contains("node2:GPP_1"));
  domain.require_clean({});
}

// The SDK mistake a build does not catch: a component whose code binds a property its PRF lacks
// exits (3) before registering, its runtime saying why in its log. The launch's error carries
// that, and the log stays reachable after the rollback through `rsca logs --failed`.
TEST_CASE("a component that exits before registering: the launch error names its node, exit code "
          "and last log lines, and rsca logs --failed shows its log",
          "[integration][domain][failure][logs]") {
  TestDomain domain(1);
  domain.install("Misbound");
  const std::string why = "property \"chatter\" is bound, but the PRF does not define it";
  auto [rc, out] = domain.cli({"launch", "Misbound"});
  INFO(out);
  CHECK(rc == 6);
  CHECK_THAT(out, Catch::Contains("failed at step 'register'"));
  CHECK_THAT(out, Catch::Contains("Misbound_1 exited before registering, on node node1"));
  CHECK_THAT(out, Catch::Contains("exited with code 3"));
  CHECK_THAT(out, Catch::Contains(why));
  CHECK_THAT(out, Catch::Contains("rolled back"));
  domain.require_clean({});
  CHECK(domain.running_pids().empty());

  // --json carries the same message.
  auto [jrc, jout] = domain.cli({"launch", "Misbound", "--json"});
  INFO(jout);
  CHECK(jrc == 6);
  const auto open = jout.find('{');
  const auto close = jout.rfind('}');
  REQUIRE(open != std::string::npos);
  REQUIRE(close != std::string::npos);
  const Json failed = Json::parse(jout.substr(open, close - open + 1));
  const std::string message = failed.at("error").at("message");
  CHECK_THAT(message, Catch::Contains("Misbound_1 exited before registering, on node node1"));
  // Only this launch's lines: its process appended them to the first launch's log.
  const auto first = message.find(why);
  CHECK(first != std::string::npos);
  CHECK(message.find(why, first + 1) == std::string::npos);
  domain.require_clean({});

  // The domain remembers the failed launches: which process each component had, on which node.
  auto remembered = domain.call("app.failed", Json{{"application", "Misbound"}});
  REQUIRE(remembered.has_value());
  INFO(remembered->dump());
  REQUIRE(remembered->at("launches").size() == 2);
  const Json &last = remembered->at("launches").back();
  CHECK(last.at("application") == "Misbound");
  CHECK(last.at("step") == "register");
  CHECK_THAT(last.at("error").get<std::string>(), Catch::Contains(why));
  REQUIRE(last.at("components").size() == 2);
  for (const auto &c : last.at("components")) {
    CHECK(c.at("node") == "node1");
    CHECK(c.at("pid").get<long>() > 0);
  }

  // The CLI reads the logs of the last failed launch from the node, through node.logs: the
  // component's whole log from this launch, its reason with it.
  auto [lrc, lout] = domain.cli({"logs", "--failed"});
  INFO(lout);
  CHECK(lrc == 0);
  CHECK_THAT(lout, Catch::Contains("Misbound_1 | "));
  CHECK_THAT(lout, Catch::Contains(why));
  auto [nrc, nout] = domain.cli({"logs", "--failed", "Misbound", "--json"});
  INFO(nout);
  CHECK(nrc == 0);
  CHECK_THAT(nout, Catch::Contains("\"component\":\"Misbound_1\""));
  auto [urc, uout] = domain.cli({"logs", "--failed", "Healthy"});
  INFO(uout);
  CHECK(urc == 3);
  CHECK_THAT(uout, Catch::Contains("no failed launch of Healthy"));
  domain.require_clean({});
}
