// Connections to device ports, and pending connections: with real node daemons, a device with a
// port (HostMonitor, run inside its node), component processes and DDS traffic.
#include "domain_fixture.hpp"

using namespace rsca::test;
using namespace std::chrono_literals;

namespace {

const fs::path kMonitorNode = kTestSdr / "dev/nodes/monitor/DeviceManager.dcd.xml";
const std::string kMonitor = "rsca/device/monitor/HostMonitor_1";

long query_long(TestDomain &domain, const std::string &app, const std::string &component,
                const std::string &id) {
  auto q = domain.call("app.query", Json{{"app", app}, {"component", component}, {"ids", {id}}});
  return q ? q->at("properties").at(id).get<long>() : -1;
}

std::string address_of(TestDomain &domain, const std::string &app, const std::string &component) {
  auto shown = domain.call("app.show", Json{{"app", app}});
  REQUIRE(shown.has_value());
  for (const auto &c : shown->at("components"))
    if (c.at("id") == component)
      return c.at("address").get<std::string>();
  return {};
}

} // namespace

TEST_CASE("a SAD connection to a port of the device a component uses carries data and is "
          "removed from the device with the application",
          "[integration][connections][devices]") {
  TestDomain domain({TestDomain::shipped_nodes(1)[0], kMonitorNode});
  domain.install("Watch");
  auto [rc, out] = domain.cli({"launch", "Watch"});
  INFO(out);
  REQUIRE(rc == 0);
  auto app = domain.call("app.show", Json{{"app", "Watch"}});
  REQUIRE(app.has_value());
  // The component runs on node1's GPP (the monitor node has none) and uses the remote device.
  CHECK(app->at("components")[0].at("device") == "node1:GPP_1");
  CHECK(app->at("connections")[0].at("uses") == "monitor:HostMonitor_1.status_out");
  CHECK(TestDomain::wait_for(
      [&] { return query_long(domain, "Watch", "Watcher_1", "events_received") > 5; }));
  CHECK(port_connections(domain, kMonitor, "status_out") == 1);

  auto list = domain.call("connection.list", Json{{"app", "Watch"}});
  REQUIRE(list.has_value());
  REQUIRE(list->at("connections").size() == 1);
  const Json &watch = list->at("connections")[0];
  CHECK(watch.at("uses_state").at("matched") == 1);
  CHECK(watch.at("uses_state").at("samples").get<long>() > 0);

  REQUIRE(domain.call("app.release", Json{{"app", "Watch"}}).has_value());
  // The device lives on, without the application's connection.
  CHECK(port_connections(domain, kMonitor, "status_out") == 0);
  domain.require_clean(pids_of(*app));
}

TEST_CASE("a SAD connection to a port of the device the application uses (deviceusedbyapplication) "
          "carries data",
          "[integration][connections][devices][redhawk22]") {
  TestDomain domain({TestDomain::shipped_nodes(1)[0], kMonitorNode});
  domain.install("WatchByApplication");
  auto [rc, out] = domain.cli({"launch", "WatchByApplication"});
  INFO(out);
  REQUIRE(rc == 0);
  auto app = domain.call("app.show", Json{{"app", "WatchByApplication"}});
  REQUIRE(app.has_value());
  CHECK(app->at("connections")[0].at("uses") == "monitor:HostMonitor_1.status_out");
  CHECK(TestDomain::wait_for([&] {
    return query_long(domain, "WatchByApplication", "Watcher_1", "events_received") > 5;
  }));
  REQUIRE(domain.call("app.release", Json{{"app", "WatchByApplication"}}).has_value());
  CHECK(port_connections(domain, kMonitor, "status_out") == 0);
  domain.require_clean(pids_of(*app));
}

TEST_CASE("a connection to a device that registers later, or to an application not launched "
          "yet, waits and is completed when it appears, and waits again when that end goes",
          "[integration][connections][devices][pending]") {
  TestDomain domain(1);
  REQUIRE(domain
              .cli({"launch",
                    (kSource / "profiles/dom/waveforms/ProducerConsumer/"
                               "ProducerConsumer.sad.xml")
                        .string(),
                    "--name", "pc"})
              .first == 0);
  const std::string consumer = address_of(domain, "pc", "Consumer_1");
  const std::string producer = address_of(domain, "pc", "Producer_1");

  // The device's node is not up: the connection waits for it.
  auto [wrc, wout] = domain.cli(
      {"connect", "monitor:HostMonitor_1.status_out", "pc/Consumer_1.events_in", "--id", "watch"});
  INFO(wout);
  REQUIRE(wrc == 0);
  CHECK_THAT(wout, Catch::Contains("pending watch"));
  CHECK(runtime_connection(domain, "watch").at("waiting_for") ==
        "device monitor:HostMonitor_1 has not registered");
  domain.start_node(kMonitorNode);
  CHECK(TestDomain::wait_for([&] { return delivered(domain, "watch") > 3; }));
  CHECK(runtime_connection(domain, "watch").at("state") == "connected");

  // An external port of pc to an application not launched yet.
  auto [trc, tout] =
      domain.cli({"connect", "pc.samples_tap", "late/Consumer_1.samples_in", "--id", "tap"});
  INFO(tout);
  REQUIRE(trc == 0);
  CHECK(runtime_connection(domain, "tap").at("waiting_for") == "application late is not running");
  // Ends that can never fit are refused at once, not left waiting.
  auto [xrc, xout] = domain.cli({"connect", "pc.nope", "late/Consumer_1.samples_in"});
  CHECK(xrc == 3);
  CHECK_THAT(xout, Catch::Contains("pc.nope is not an external uses port"));
  REQUIRE(domain.cli({"launch", "ProducerConsumer", "--name", "late"}).first == 0);
  CHECK(TestDomain::wait_for([&] { return delivered(domain, "tap") > 3; }));
  CHECK(port_connections(domain, producer, "samples_out") == 2);

  // Its application released: the tap waits again, pc's producer keeps only its own connection.
  auto late = domain.call("app.show", Json{{"app", "late"}});
  REQUIRE(late.has_value());
  REQUIRE(domain.call("app.release", Json{{"app", "late"}}).has_value());
  CHECK(runtime_connection(domain, "tap").at("waiting_for") == "late is gone");
  CHECK(port_connections(domain, producer, "samples_out") == 1);

  // The device's node dies: the connection waits for it, the consumer's end is removed.
  domain.kill_node(2);
  CHECK(TestDomain::wait_for(
      [&] { return runtime_connection(domain, "watch").at("state") == "pending"; }));
  CHECK(TestDomain::wait_for([&] { return port_connections(domain, consumer, "events_in") == 0; }));
  // ... and is completed again when it comes back.
  domain.start_node(kMonitorNode);
  CHECK(TestDomain::wait_for(
      [&] { return runtime_connection(domain, "watch").at("state") == "connected"; }));
  CHECK(port_connections(domain, consumer, "events_in") == 1);

  for (const char *id : {"watch", "tap"})
    REQUIRE(domain.cli({"disconnect", id}).first == 0);
  CHECK(port_connections(domain, consumer, "events_in") == 0);
  CHECK(port_connections(domain, kMonitor, "status_out") == 0);
  auto pc = domain.call("app.show", Json{{"app", "pc"}});
  REQUIRE(pc.has_value());
  REQUIRE(domain.call("app.release", Json{{"app", "pc"}}).has_value());
  auto pids = pids_of(*pc);
  for (long pid : pids_of(*late))
    pids.push_back(pid);
  domain.require_clean(pids);
}

TEST_CASE("a SAD connection to a device port of the wrong type is refused before start",
          "[integration][connections][devices][failure]") {
  TestDomain domain({TestDomain::shipped_nodes(1)[0], kMonitorNode});
  domain.install("WatchWrongType");
  auto [rc, out] = domain.cli({"launch", "WatchWrongType"});
  INFO(out);
  CHECK(rc != 0);
  CHECK_THAT(out, Catch::Contains("failed at step 'connect'"));
  CHECK_THAT(out, Catch::Contains("connection watch: port type: device port "
                                  "monitor:HostMonitor_1.status_out carries "
                                  "IDL:rsca/PropertyEvent:1.0, but the other end carries "
                                  "IDL:rsca/SampleSeq:1.0"));
  CHECK(port_connections(domain, kMonitor, "status_out") == 0);
  domain.require_clean({});
}
