// What a hostile test of the daemons found (issue 18), each as it was found: real daemons, real
// processes, requests sent as a client on the network could send them.
#include <csignal>
#include <future>

#include "dds/dds_settings.hpp"
#include "domain_fixture.hpp"
#include "profile/profile_loader.hpp"

using namespace rsca::test;

namespace {

// The install request the CLI would send for an application of the test SDR root, before any
// check of the CLI's own: what any client on the network can send.
Json install_request(const std::string &application) {
  rsca::profile::ProfileLoader loader(kTestSdr);
  auto app = loader.load_application(kTestSdr / "dom/waveforms" / application /
                                     (application + ".sad.xml"));
  REQUIRE(app.has_value());
  Json files = Json::array();
  for (const auto &f : app->files())
    files.push_back({{"path", f.lexically_relative(kTestSdr).string()}, {"content", read_file(f)}});
  return {{"sad", app->sad_path.lexically_relative(kTestSdr).string()}, {"files", files}};
}

void set_sad_name(Json &request, const std::string &name) {
  for (auto &f : request.at("files"))
    if (f.at("path") == request.at("sad")) {
      std::string content = f.at("content");
      const auto at = content.find(" name=\"");
      REQUIRE(at != std::string::npos);
      const auto end = content.find('"', at + 7);
      content.replace(at + 7, end - at - 7, name);
      f["content"] = content;
    }
}

// Files and folders in the repository's staging area.
std::size_t staged(const fs::path &repository) {
  if (!fs::exists(repository / ".staging"))
    return 0;
  return static_cast<std::size_t>(
      std::distance(fs::directory_iterator(repository / ".staging"), fs::directory_iterator()));
}

const Json &component(const Json &app, const std::string &id) {
  for (const auto &c : app.at("components"))
    if (c.at("id") == id)
      return c;
  FAIL("no component " << id);
  throw std::logic_error("unreachable");
}

void refused_as_bad_request(const rsca::control::CallResult<Json> &reply,
                            const std::string &saying) {
  REQUIRE_FALSE(reply.has_value());
  CHECK(reply.error().status == Status::BadRequest);
  CHECK_THAT(reply.error().message, Catch::Contains(saying));
}

} // namespace

TEST_CASE("an application name that is a path never makes the domain act outside its repository",
          "[integration][hostile]") {
  TestDomain domain;
  domain.install("Healthy");
  const fs::path repository = domain.run_dir() / "repository";
  const fs::path victim = domain.run_dir() / "victim";
  fs::create_directories(victim);
  std::ofstream(victim / "precious") << "keep me";
  auto victim_intact = [&] { return read_file(victim / "precious") == "keep me"; };

  for (const std::string name : {"../victim", "../../victim", ".", "..", "a/b", ".staging"}) {
    INFO("install --name " << name);
    Json request = install_request("Healthy");
    request["name"] = name;
    auto installed = domain.call("domain.install", request);
    REQUIRE_FALSE(installed.has_value());
    CHECK(installed.error().status == Status::BadRequest);
    CHECK_THAT(installed.error().message, Catch::Contains("is not a name"));
  }
  SECTION("a SAD whose name is a path") {
    Json request = install_request("Healthy");
    set_sad_name(request, "../victim");
    auto installed = domain.call("domain.install", request);
    REQUIRE_FALSE(installed.has_value());
    CHECK(installed.error().status == Status::BadRequest);
    CHECK_THAT(installed.error().message, Catch::Contains("application-name"));
  }
  SECTION("a SAD whose name is 7 MB long: refused, quoted in part, nothing staged") {
    Json request = install_request("Healthy");
    set_sad_name(request, std::string(7 * 1024 * 1024, 'n'));
    auto installed = domain.call("domain.install", request, 60s);
    REQUIRE_FALSE(installed.has_value());
    CHECK(installed.error().message.size() < 4096);
  }
  SECTION("uninstall of a path") {
    for (const std::string name : {"../victim", ".", ".."}) {
      INFO("uninstall " << name);
      auto removed = domain.call("domain.uninstall", Json{{"name", name}});
      REQUIRE_FALSE(removed.has_value());
      CHECK(removed.error().status == Status::BadRequest);
    }
  }
  CHECK(victim_intact());
  CHECK(staged(repository) == 0);
  // The repository lost nothing: its store and what was installed survive a restart.
  domain.restart_domaind();
  auto installed = domain.call("domain.installed");
  REQUIRE(installed.has_value());
  REQUIRE(installed->at("applications").size() == 1);
  CHECK(installed->at("applications")[0].at("name") == "Healthy");
}

TEST_CASE("uninstall while a launch of the application is under way is refused, the domain lives "
          "on and forgets the application for good once uninstalled",
          "[integration][hostile]") {
  TestDomain domain(2, /*registration_timeout_ms=*/60000); // the launch waits until cancelled
  domain.install("NeverRegisters");
  auto launch = std::async(std::launch::async, [&] {
    return domain.call("app.create", Json{{"application", "NeverRegisters"}, {"launch_id", "L"}},
                       90s);
  });
  REQUIRE(TestDomain::wait_for([&] {
    auto progress = domain.call("app.progress", Json{{"launch_id", "L"}});
    return progress && progress->at("steps").size() >= 3; // check, allocate, execute: registering
  }));
  auto refused = domain.call("domain.uninstall", Json{{"name", "NeverRegisters"}});
  REQUIRE_FALSE(refused.has_value());
  CHECK(refused.error().status == Status::Rejected);
  CHECK_THAT(refused.error().message, Catch::Contains("under way"));
  REQUIRE(domain.call("domain.nodes").has_value()); // still serving

  REQUIRE(domain.call("app.cancel", Json{{"launch_id", "L"}}).has_value());
  auto launched = launch.get();
  REQUIRE_FALSE(launched.has_value());
  REQUIRE(domain.call("domain.uninstall", Json{{"name", "NeverRegisters"}}).has_value());
  domain.restart_domaind();
  auto installed = domain.call("domain.installed");
  REQUIRE(installed.has_value());
  CHECK(installed->at("applications").empty());
  domain.require_clean({});
}

TEST_CASE("a request with a field the domain does not know is refused, naming the field, before "
          "anything is done",
          "[integration][hostile]") {
  TestDomain domain;
  domain.install("Healthy");
  // A client's typo ("stratgy"): taken without it, the launch would run on the default strategy.
  refused_as_bad_request(
      domain.call("app.create", Json{{"application", "Healthy"}, {"stratgy", "spread"}}),
      "app.create: unknown field \"stratgy\"");
  auto apps = domain.call("app.list");
  REQUIRE(apps.has_value());
  CHECK(apps->at("applications").empty());
  CHECK(domain.running_pids().empty());

  refused_as_bad_request(
      domain.call("app.show", Json{{"app", "Healthy"}, {"component", "Producer_1"}}),
      "app.show: unknown field \"component\"");
  refused_as_bad_request(domain.call("app.query", Json{{"app", "Healthy"}, {"ids", "received"}}),
                         "app.query: field \"ids\": expected an array, found string");
}

TEST_CASE("a restarted domain daemon never collides with what a killed one left running, and "
          "reports it",
          "[integration][hostile][recovery]") {
  TestDomain domain;
  domain.install("Healthy");
  auto first = domain.call("app.create", Json{{"application", "Healthy"}, {"name", "H"}});
  REQUIRE(first.has_value());
  const auto orphans = pids_of(*first);
  domain.kill_domaind();
  domain.start_domaind(TestDomain::kRegistrationTimeoutMs);
  REQUIRE(TestDomain::wait_for([&] {
    auto nodes = domain.call("domain.nodes", Json::object(), 2s);
    return nodes && nodes->at("nodes").size() == 2;
  }));
  // What runs without an application of this domain daemon is reported.
  CHECK(TestDomain::wait_for([&] {
    auto apps = domain.call("app.list");
    return apps && apps->at("applications").empty() &&
           apps->at("unknown").size() == first->at("components").size();
  }));
  auto second = domain.call("app.create", Json{{"application", "Healthy"}, {"name", "H"}});
  REQUIRE(second.has_value());
  for (const auto &c : second->at("components")) {
    INFO(c.at("address"));
    CHECK(c.at("address") != component(*first, c.at("id")).at("address"));
  }
  for (std::size_t i = 0; i < second->at("connections").size(); ++i)
    CHECK(second->at("connections")[i].at("topic") != first->at("connections")[i].at("topic"));
  // Releasing the new one leaves the old processes alone (the operator decides about them).
  REQUIRE(domain.call("app.release", Json{{"app", "H"}}).has_value());
  for (long pid : orphans)
    CHECK(process_exists(pid));
  for (long pid : orphans)
    ::kill(static_cast<pid_t>(pid), SIGKILL);
  std::vector<long> all = orphans;
  for (long pid : pids_of(*second))
    all.push_back(pid);
  domain.require_clean(all);
}

TEST_CASE("an application with a dead component is degraded, listing its connections and "
          "stopping it answer at once",
          "[integration][hostile]") {
  TestDomain domain;
  const Json app = domain.create("Healthy");
  const long producer = component(app, "Producer_1").at("pid").get<long>();
  ::kill(static_cast<pid_t>(producer), SIGKILL);
  REQUIRE(TestDomain::wait_for([&] {
    auto apps = domain.call("app.list");
    return apps && apps->at("applications").size() == 1 &&
           apps->at("applications")[0].at("state") == "degraded";
  }));
  auto listed = domain.call("app.list");
  REQUIRE(listed.has_value());
  CHECK(listed->at("applications")[0].at("exited") == Json::array({"Producer_1"}));

  // The domain answers with what it knows, within the CLI's default wait.
  auto [lrc, lout] = domain.cli({"ls", "connections"});
  INFO(lout);
  CHECK(lrc == 0);
  CHECK_THAT(lout, Catch::Contains("Healthy/feed"));

  auto [src, sout] = domain.cli({"stop", "Healthy"});
  INFO(sout);
  CHECK(src == 0);
  auto shown = domain.call("app.show", Json{{"app", "Healthy"}});
  REQUIRE(shown.has_value());
  CHECK(shown->at("state") == "degraded");
  CHECK(component(*shown, "Producer_1").at("state") == "exited");
  CHECK(component(*shown, "Victim_1").at("state") == "stopped");
  auto [vrc, vout] = domain.cli({"show", "Healthy"});
  CHECK_THAT(vout, Catch::Contains("degraded: exited Producer_1"));

  REQUIRE(domain.call("app.release", Json{{"app", "Healthy"}}).has_value());
  domain.require_clean(pids_of(app));
}

TEST_CASE("concurrent stops and starts of one application leave its record as its components are",
          "[integration][hostile]") {
  TestDomain domain;
  const Json app = domain.create("Healthy");
  const std::string controller = component(app, "Victim_1").at("address");
  for (int round = 0; round < 20; ++round) {
    INFO("round " << round);
    auto stop = std::async(std::launch::async, [&] {
      return domain.call("app.stop", Json{{"app", "Healthy"}});
    });
    auto start = std::async(std::launch::async, [&] {
      return domain.call("app.start", Json{{"app", "Healthy"}});
    });
    REQUIRE(stop.get().has_value());
    REQUIRE(start.get().has_value());
    auto shown = domain.call("app.show", Json{{"app", "Healthy"}});
    REQUIRE(shown.has_value());
    auto status = domain.client().call_sync(controller, "component.status", Json::object(), 5s);
    REQUIRE(status.has_value());
    const bool recorded_running = component(*shown, "Victim_1").at("state") == "running";
    CHECK(recorded_running == (status->at("state") == "started"));
    CHECK((shown->at("state") == "running") == recorded_running);
  }
  REQUIRE(domain.call("app.release", Json{{"app", "Healthy"}}).has_value());
  domain.require_clean(pids_of(app));
}

TEST_CASE("a launch whose domain daemon dies says so within a lease, not after its whole wait",
          "[integration][hostile][recovery]") {
  TestDomain domain(2, /*registration_timeout_ms=*/60000); // the launch waits for Victim_1
  domain.install("NeverRegisters");
  // The CLI waits up to six times --timeout-ms (here 10 minutes) for a launch.
  auto launch = std::async(std::launch::async, [&] {
    return domain.cli({"--timeout-ms", "100000", "launch", "NeverRegisters"});
  });
  std::vector<long> orphans;
  REQUIRE(TestDomain::wait_for([&] {
    orphans = domain.running_pids();
    return orphans.size() == 2; // executed: the launch waits for Victim_1 to register
  }));
  domain.kill_domaind();
  // Within a few leases of the daemons' participants (the CLI's own settings, read as it reads
  // them; 1 s), room left for a loaded host: far below a call's timeout (100 s) or the launch's
  // whole wait (10 min), either of which a CLI that missed the domain's death would wait out.
  const auto lease = rsca::dds::DdsSettings::from_environment().timing.lease;
  REQUIRE(launch.wait_for(10 * lease) == std::future_status::ready);
  auto [rc, out] = launch.get();
  INFO(out);
  CHECK(rc == 4); // unreachable
  CHECK_THAT(out, Catch::Contains("rsca/domain left before it replied to \"app.create\""));
  CHECK_THAT(out, Catch::Contains("may still run"));

  // What the dead daemon started is the operator's to stop (a restarted one reports it).
  for (long pid : orphans)
    ::kill(static_cast<pid_t>(pid), SIGKILL);
  domain.start_domaind(TestDomain::kRegistrationTimeoutMs);
  REQUIRE(TestDomain::wait_for([&] {
    auto nodes = domain.call("domain.nodes", Json::object(), 2s);
    return nodes && nodes->at("nodes").size() == 2;
  }));
  domain.require_clean(orphans);
}

TEST_CASE("a node announcement that does not fit the contract is refused and listed, never used",
          "[integration][hostile]") {
  TestDomain domain;
  auto nodes = [&domain] {
    auto listed = domain.call("domain.nodes");
    REQUIRE(listed.has_value());
    return *listed;
  };
  const auto before = nodes().at("nodes").size();
  // Another endpoint on the domain's DDS domain claims to be a node, with its devices a string.
  auto rogue = rsca::control::Endpoint::open(rsca::test::participant(), "rsca/node/rogue");
  REQUIRE(rogue.has_value());
  REQUIRE((*rogue)
              ->announce("node",
                         Json{{"node", "rogue"}, {"pid", 1}, {"host", "h"}, {"devices", "lots"}})
              .has_value());
  REQUIRE(TestDomain::wait_for([&] { return !nodes().value("refused", Json::array()).empty(); }));
  const Json listed = nodes();
  CHECK(listed.at("nodes").size() == before);
  const Json &refused = listed.at("refused").at(0);
  CHECK(refused.at("address") == "rsca/node/rogue");
  CHECK_THAT(refused.at("why").get<std::string>(), Catch::Contains("field \"devices\""));
  auto devices = domain.call("domain.devices");
  REQUIRE(devices.has_value());
  for (const auto &d : devices->at("devices"))
    CHECK(d.at("node") != "rogue");
  auto [rc, out] = domain.cli({"ls", "nodes"});
  CHECK(rc == 0);
  CHECK_THAT(out, Catch::Contains("refused: the endpoint at rsca/node/rogue"));

  // Once it is gone, it is no longer listed.
  rogue->reset();
  CHECK(TestDomain::wait_for([&] { return nodes().value("refused", Json::array()).empty(); }));
}
