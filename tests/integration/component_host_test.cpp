// Shared-library components in component hosts, with real daemons and processes: one host
// process per application and device, connected to component processes and to each other over
// the same ports, released or rolled back with nothing left.
#include <filesystem>
#include <fstream>
#include <map>

#include "domain_fixture.hpp"

namespace {

using namespace rsca::test;

// The name of the executable a process runs.
std::string executable_of(long pid) {
  std::error_code ec;
  return fs::read_symlink(fmt::format("/proc/{}/exe", pid), ec).filename().string();
}

// Whether each connection of the application is in-host, by id, from both ends' live state.
std::map<std::string, bool> in_host_by_connection(TestDomain &domain, const std::string &app) {
  auto list = domain.call("connection.list", Json{{"app", app}});
  REQUIRE(list.has_value());
  std::map<std::string, bool> in_host;
  for (const auto &c : list->at("connections")) {
    const bool uses = c.at("uses_state").value("in_host", false);
    const bool provides = c.at("provides_state").value("in_host", false);
    CHECK(uses == provides);
    in_host[c.at("id")] = uses && provides;
  }
  return in_host;
}

// The threads of a process by name, each with the CPUs it may run on (Cpus_allowed_list).
std::map<std::string, std::string> threads_of(long pid) {
  std::map<std::string, std::string> threads;
  for (const auto &task : fs::directory_iterator(fmt::format("/proc/{}/task", pid))) {
    std::ifstream status(task.path() / "status");
    std::string line, name, allowed;
    while (std::getline(status, line)) {
      if (line.rfind("Name:", 0) == 0)
        name = line.substr(line.find_first_not_of(" \t", 5));
      if (line.rfind("Cpus_allowed_list:", 0) == 0)
        allowed = line.substr(line.find_first_not_of(" \t", 18));
    }
    threads[name] = allowed;
  }
  return threads;
}

// The pid of each component, by id.
std::map<std::string, long> pids_by_component(const Json &app) {
  std::map<std::string, long> pids;
  for (const auto &c : app.at("components"))
    pids[c.at("id")] = c.at("pid").get<long>();
  return pids;
}

} // namespace

TEST_CASE("shared-library components run in one component host: launched, carrying data, "
          "configured, released with nothing left",
          "[integration][host]") {
  TestDomain domain;
  auto [rc, out] = domain.cli({"launch", (kSource / "profiles/dom/waveforms/ProducerConsumerHosted/"
                                                    "ProducerConsumerHosted.sad.xml")
                                             .string()});
  INFO(out);
  REQUIRE(rc == 0);
  auto app = domain.call("app.show", Json{{"app", "ProducerConsumerHosted"}});
  REQUIRE(app.has_value());
  CHECK(app->at("state") == "running");
  const auto pids = pids_by_component(*app);
  REQUIRE(pids.size() == 2);
  // Both are placed on one device, so one host process serves both.
  CHECK(pids.at("Producer_1") == pids.at("Consumer_1"));
  CHECK(process_exists(pids.at("Producer_1")));
  CHECK(executable_of(pids.at("Producer_1")) == "rsca-component-host");

  CHECK(TestDomain::wait_for([&] { return received(domain, "ProducerConsumerHosted") > 20; }));
  // Producer_1 is periodic: its own threads run on the CPU admission chose, the host's do not.
  for (const auto &c : app->at("components"))
    if (c.at("id") == "Producer_1") {
      const std::string cpu = std::to_string(c.at("schedule").at("cpu").get<int>());
      const auto threads = threads_of(pids.at("Producer_1"));
      REQUIRE(threads.contains("rx:Producer_1"));
      REQUIRE(threads.contains("svc:Producer_1"));
      CHECK(threads.at("rx:Producer_1") == cpu);
      CHECK(threads.at("svc:Producer_1") == cpu);
      REQUIRE(threads.contains("rx:Consumer_1"));
      CHECK(threads.at("rx:Consumer_1") != cpu);
    }
  // Two components of one host: the data bypasses DDS.
  CHECK(in_host_by_connection(domain, "ProducerConsumerHosted") ==
        std::map<std::string, bool>{{"samples", true}});
  auto [crc, configured] =
      domain.cli({"configure", "ProducerConsumerHosted/Producer_1", "rate_hz=200"});
  INFO(configured);
  CHECK(crc == 0);
  auto q = domain.call(
      "app.query",
      Json{{"app", "ProducerConsumerHosted"}, {"component", "Producer_1"}, {"ids", {"rate_hz"}}});
  REQUIRE(q.has_value());
  CHECK(q->at("properties").at("rate_hz").get<double>() == 200.0);

  // A runtime connection between the two takes the same in-host path, and filters as a SAD
  // connection does: no sample is the end of a stream, so every one is filtered out.
  const Json ends{{"uses",
                   {{"application", "ProducerConsumerHosted"},
                    {"component", "Producer_1"},
                    {"port", "samples_out"}}},
                  {"provides",
                   {{"application", "ProducerConsumerHosted"},
                    {"component", "Consumer_1"},
                    {"port", "samples_in"}}}};
  Json request = ends;
  request["id"] = "filtered";
  request["filter"] = "end_of_stream";
  auto made = domain.call("connection.create", request);
  REQUIRE(made.has_value());
  CHECK(made->at("state") == "connected");
  CHECK(made->at("filter") == "end_of_stream");
  auto runtime_state = [&domain] {
    auto list = domain.call("connection.list", Json{{"app", "ProducerConsumerHosted"}});
    REQUIRE(list.has_value());
    for (const auto &c : list->at("connections"))
      if (c.at("id") == "filtered")
        return c;
    FAIL("the runtime connection is not listed");
    return Json();
  };
  CHECK(TestDomain::wait_for(
      [&] { return runtime_state().at("provides_state").value("filtered", 0) > 5; }));
  const Json state = runtime_state();
  CHECK(state.at("uses_state").value("in_host", false));
  CHECK(state.at("provides_state").value("in_host", false));
  // Every sample that arrived was filtered (one may be between the two counts).
  const auto arrived = state.at("provides_state").value("samples", 0);
  CHECK(arrived - state.at("provides_state").value("filtered", 0) <= 1);
  // A filter that does not parse is refused before anything is made or kept.
  request["id"] = "unparsable";
  request["filter"] = "range <";
  auto refused = domain.call("connection.create", request);
  REQUIRE_FALSE(refused.has_value());
  CHECK_THAT(refused.error().message, Catch::StartsWith("filter: "));

  REQUIRE(domain.call("app.release", Json{{"app", "ProducerConsumerHosted"}}).has_value());
  REQUIRE(domain.call("connection.destroy", Json{{"id", "filtered"}}).has_value());
  domain.require_clean({pids.at("Producer_1")});
}

TEST_CASE("hosted components and component processes connect to each other",
          "[integration][host]") {
  TestDomain domain;
  const Json app = domain.create("HostedMixed");
  const auto pids = pids_by_component(app);
  std::map<std::string, std::string> device;
  for (const auto &c : app.at("components"))
    device[c.at("id")] = c.at("device");
  // The two hosted producers share a host when they share a device; the consumer is a process.
  CHECK((pids.at("Producer_1") == pids.at("Producer_2")) ==
        (device.at("Producer_1") == device.at("Producer_2")));
  CHECK(pids.at("Consumer_1") != pids.at("Producer_1"));
  CHECK(executable_of(pids.at("Consumer_1")) == "rsca-consumer");
  CHECK(executable_of(pids.at("Producer_1")) == "rsca-component-host");
  CHECK(TestDomain::wait_for([&] { return received(domain, "HostedMixed") > 20; }));
  // Between a host and a process every connection is a DDS one.
  for (const auto &[id, in_host] : in_host_by_connection(domain, "HostedMixed")) {
    INFO(id);
    CHECK_FALSE(in_host);
  }
  REQUIRE(domain.call("app.release", Json{{"app", "HostedMixed"}}).has_value());
  domain.require_clean(pids_of(app));
}

TEST_CASE("a component host that cannot load a library fails the launch, which rolls back "
          "everything",
          "[integration][host][failure]") {
  TestDomain domain;
  // The library is delivered (it is there) but is text, not a shared object: the host starts
  // and its dlopen fails.
  domain.install("UnloadableLibrary");
  auto [rc, out] = domain.cli({"launch", "UnloadableLibrary"});
  INFO(out);
  CHECK(rc == 6);
  CHECK_THAT(out, Catch::Contains("failed at step 'register'"));
  CHECK_THAT(out, Catch::Contains("Consumer_1 exited before registering"));
  // The processes started (the host's, the producers') were ended.
  CHECK_THAT(out, Catch::Contains("processes terminated"));
  // The host said why, in its log.
  std::string logs;
  for (const auto &entry : fs::recursive_directory_iterator(domain.run_dir() / "logs"))
    if (entry.is_regular_file()) {
      std::ifstream in(entry.path());
      logs.append(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
  CHECK_THAT(logs, Catch::Contains("cannot load") && Catch::Contains("librsca-unloadable.so"));
  domain.require_clean({});
}

TEST_CASE("a hosted component whose library is missing fails the launch before any process "
          "starts",
          "[integration][host][failure]") {
  TestDomain domain;
  domain.install("MissingLibrary");
  auto [rc, out] = domain.cli({"launch", "MissingLibrary"});
  INFO(out);
  CHECK(rc == 6);
  CHECK_THAT(out, Catch::Contains("failed at step"));
  CHECK_THAT(out, Catch::Contains("Consumer_1"));
  // The domain finds no library to deliver for Consumer_1 before any process starts: nothing
  // stays allocated, no application is left.
  CHECK_THAT(out, Catch::Contains("librsca-not-built.so"));
  domain.require_clean({});
}
