// Event channels with real daemons and components: created on first use, shared across
// applications, destroyed with their last member (down to the DDS entities), filtered per
// subscriber, and refused before anything runs when their members could never match.
#include <dds/dds.h>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <set>

#include "domain_fixture.hpp"

using namespace rsca::test;
using namespace std::chrono_literals;
using rsca::control::Json;

namespace {

const std::string kTicksTopic = "rsca_rsca_channel_Ticks";

// Counts the live DDS writers and readers on `topic` in the test's DDS domain, from the
// built-in discovery topics: what a channel's members really left behind.
class DdsEndpoints {
public:
  DdsEndpoints() : participant_(participant()) {
    writers_ =
        dds_create_reader(participant_->get(), DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
    readers_ = dds_create_reader(participant_->get(), DDS_BUILTIN_TOPIC_DCPSSUBSCRIPTION, nullptr,
                                 nullptr);
    REQUIRE(writers_ > 0);
    REQUIRE(readers_ > 0);
  }
  ~DdsEndpoints() {
    dds_delete(writers_);
    dds_delete(readers_);
  }

  std::size_t on(const std::string &topic) const {
    return count(writers_, topic) + count(readers_, topic);
  }

private:
  static std::size_t count(dds_entity_t reader, const std::string &topic) {
    constexpr std::size_t kMax = 256;
    void *samples[kMax] = {nullptr};
    dds_sample_info_t infos[kMax];
    const dds_return_t n =
        dds_read_mask(reader, samples, infos, kMax, kMax,
                      DDS_ANY_SAMPLE_STATE | DDS_ANY_VIEW_STATE | DDS_ALIVE_INSTANCE_STATE);
    std::size_t found = 0;
    for (dds_return_t i = 0; i < n; ++i) {
      const auto *e = static_cast<const dds_builtintopic_endpoint_t *>(samples[i]);
      if (infos[i].valid_data && e->topic_name != nullptr && topic == e->topic_name)
        ++found;
    }
    if (n > 0)
      dds_return_loan(reader, samples, n);
    return found;
  }

  std::shared_ptr<rsca::dds::Participant> participant_;
  dds_entity_t writers_ = 0;
  dds_entity_t readers_ = 0;
};

long property(TestDomain &domain, const std::string &target, const std::string &id) {
  const auto slash = target.find('/');
  auto q = domain.call("app.query", Json{{"app", target.substr(0, slash)},
                                         {"component", target.substr(slash + 1)},
                                         {"ids", {id}}});
  return q ? q->at("properties").at(id).get<long>() : -1;
}

// The component processes of the running applications `names`.
std::vector<long> pids_of_applications(TestDomain &domain,
                                       std::initializer_list<const char *> names) {
  std::vector<long> pids;
  for (const char *name : names) {
    auto app = domain.call("app.show", Json{{"app", name}});
    REQUIRE(app.has_value());
    for (long pid : pids_of(*app))
      pids.push_back(pid);
  }
  return pids;
}

Json channel(TestDomain &domain, const std::string &name) {
  auto list = domain.call("channel.list");
  REQUIRE(list.has_value());
  for (const auto &c : list->at("channels"))
    if (c.at("name") == name)
      return c;
  return nullptr;
}

} // namespace

TEST_CASE("an event channel carries events to every subscriber, and a filtered one gets only what "
          "matches",
          "[integration][channels]") {
  TestDomain domain;
  const auto pids = pids_of(domain.create("Events"));

  // Consumer_1 takes every tick (100 a second); Consumer_2's filter "sequence < 50" lets the first
  // fifty through and no other. (The very first ticks may be written before a reader is matched,
  // so the test does not count on all fifty.)
  CHECK(TestDomain::wait_for(
      [&] { return property(domain, "Events/Consumer_1", "events_received") > 80; }));
  const long first_fifty = property(domain, "Events/Consumer_2", "events_received");
  CHECK(first_fifty >= 1);
  CHECK(first_fifty <= 50);
  auto connections = domain.call("connection.list", Json{{"app", "Events"}});
  REQUIRE(connections.has_value());
  for (const auto &c : connections->at("connections")) {
    if (c.at("id") != "first_fifty")
      continue;
    CHECK(c.at("filter") == "sequence < 50");
    CHECK(c.at("provides_state").at("matched") == 1);
    CHECK(c.at("provides_state").at("filtered").get<long>() > 20);
  }
  const Json ticks = channel(domain, "Ticks");
  REQUIRE_FALSE(ticks.is_null());
  CHECK(ticks.at("publishers") == 1);
  CHECK(ticks.at("subscribers") == 2);
  CHECK(ticks.at("topic") == kTicksTopic);

  REQUIRE(domain.call("app.release", Json{{"app", "Events"}}).has_value());
  CHECK(channel(domain, "Ticks").is_null());
  domain.require_clean(pids);
}

TEST_CASE("an event channel with members on two nodes is one DDS topic that each node fans out",
          "[integration][channels]") {
  TestDomain domain(2);
  DdsEndpoints dds;
  domain.install("Events");
  auto [rc, out] = domain.cli({"launch", "Events", "--strategy", "spread"});
  INFO(out);
  REQUIRE(rc == 0);
  const Json app = domain.call("app.show", Json{{"app", "Events"}}).value();
  INFO(app.dump());
  const auto pids = pids_of(app);
  std::set<std::string> publishing, subscribing; // nodes
  for (const auto &c : app.at("components"))
    (c.at("id") == "Producer_1" ? publishing : subscribing).insert(c.at("node").get<std::string>());
  REQUIRE(publishing.size() + subscribing.size() > 2); // spread: members on both nodes
  CHECK(TestDomain::wait_for(
      [&] { return property(domain, "Events/Consumer_1", "events_received") > 20; }));
  CHECK(TestDomain::wait_for(
      [&] { return property(domain, "Events/Consumer_2", "events_received") > 0; }));
  // Only the nodes' relays are on the topic: a writer where the publisher is, a reader on each
  // node with subscribers; the component processes have no DDS of their own.
  CHECK(TestDomain::wait_for(
      [&] { return dds.on(kTicksTopic) == publishing.size() + subscribing.size(); }));
  REQUIRE(domain.call("app.release", Json{{"app", "Events"}}).has_value());
  CHECK(TestDomain::wait_for([&] { return dds.on(kTicksTopic) == 0; }));
  domain.require_clean(pids); // every node's rings and relays gone
}

TEST_CASE("a channel shared by two applications outlives the first and goes with the second, DDS "
          "entities and all",
          "[integration][channels]") {
  TestDomain domain;
  DdsEndpoints dds;
  domain.install("Events");
  domain.install("TickListener");
  auto events = domain.call("app.create", Json{{"application", "Events"}});
  REQUIRE(events.has_value());
  auto listener = domain.call("app.create", Json{{"application", "TickListener"}});
  REQUIRE(listener.has_value());
  auto pids = pids_of(*events);
  for (long pid : pids_of(*listener))
    pids.push_back(pid);
  CHECK(channel(domain, "Ticks").at("subscribers") == 3);
  CHECK(TestDomain::wait_for(
      [&] { return property(domain, "TickListener/Listener_1", "events_received") > 5; }));
  // The channel is one DDS topic, fanned out by each node: the publisher and the three
  // subscribers are on node1, whose relay is the topic's one writer and one reader.
  CHECK(TestDomain::wait_for([&] { return dds.on(kTicksTopic) == 2; }));

  REQUIRE(domain.call("app.release", Json{{"app", "Events"}}).has_value());
  const Json ticks = channel(domain, "Ticks");
  REQUIRE_FALSE(ticks.is_null());
  CHECK(ticks.at("publishers") == 0);
  CHECK(ticks.at("subscribers") == 1);
  CHECK(TestDomain::wait_for([&] { return dds.on(kTicksTopic) == 1; }));

  REQUIRE(domain.call("app.release", Json{{"app", "TickListener"}}).has_value());
  CHECK(channel(domain, "Ticks").is_null());
  CHECK(TestDomain::wait_for([&] { return dds.on(kTicksTopic) == 0; }));
  domain.require_clean(pids);
}

TEST_CASE("channel members that could never match are refused before anything runs",
          "[integration][channels][failure]") {
  TestDomain domain;
  domain.install("QosMismatch");
  domain.install("MixedChannel");
  auto [qrc, qout] = domain.cli({"launch", "QosMismatch"});
  INFO(qout);
  CHECK(qrc == 1);
  CHECK_THAT(qout, Catch::Contains("failed at step 'check'"));
  CHECK_THAT(qout,
             Catch::Contains("publisher QosMismatch/Producer_1.events_out (connection publish)"));
  CHECK_THAT(qout,
             Catch::Contains("subscriber QosMismatch/Consumer_1.events_in (connection subscribe)"));
  CHECK_THAT(qout, Catch::Contains(
                       "reliability: the writer offers besteffort, the reader requests reliable"));
  auto [mrc, mout] = domain.cli({"launch", "MixedChannel"});
  INFO(mout);
  CHECK(mrc == 1);
  CHECK_THAT(mout, Catch::Contains(
                       "port type: MixedChannel/Producer_1.events_out is "
                       "IDL:rsca/PropertyEvent:1.0, channel Mixed carries IDL:rsca/SampleSeq:1.0"));
  // Nothing ran, and neither channel stayed.
  auto list = domain.call("channel.list");
  REQUIRE(list.has_value());
  CHECK(list->at("channels").empty());
  domain.require_clean({});
}

TEST_CASE("an operator's channel lives until the operator destroys it", "[integration][channels]") {
  TestDomain domain;
  auto [crc, cout_text] = domain.cli({"channel", "create", "Ticks"});
  INFO(cout_text);
  REQUIRE(crc == 0);
  CHECK(channel(domain, "Ticks").at("operator") == true);
  domain.install("Events");
  auto app = domain.call("app.create", Json{{"application", "Events"}});
  REQUIRE(app.has_value());
  // In use: not destroyed under the application.
  auto [drc, dout] = domain.cli({"channel", "destroy", "Ticks"});
  CHECK(drc == 5);
  CHECK_THAT(dout, Catch::Contains("event channel Ticks is in use by Events"));
  REQUIRE(domain.call("app.release", Json{{"app", "Events"}}).has_value());
  CHECK_FALSE(channel(domain, "Ticks").is_null()); // the release leaves the operator's channel
  auto [rrc, rout] = domain.cli({"channel", "destroy", "Ticks"});
  INFO(rout);
  CHECK(rrc == 0);
  CHECK(channel(domain, "Ticks").is_null());
  auto [nrc, nout] = domain.cli({"channel", "destroy", "Ticks"});
  CHECK(nrc == 3);
  domain.require_clean(pids_of(*app));
}

TEST_CASE("runtime connections between running applications: made, checked, carrying data, "
          "removed, and gone with an application",
          "[integration][connections]") {
  TestDomain domain;
  const auto sad =
      (kSource / "profiles/dom/waveforms/ProducerConsumer/ProducerConsumer.sad.xml").string();
  auto [arc, aout] = domain.cli({"launch", sad, "--name", "a"});
  REQUIRE(arc == 0);
  auto [brc, bout] = domain.cli({"launch", "ProducerConsumer", "--name", "b"});
  REQUIRE(brc == 0);
  const std::vector<long> pids = pids_of_applications(domain, {"a", "b"});

  // a's producer feeds b's consumer too, with the QoS asked for.
  auto [rc, out] =
      domain.cli({"connect", "a/Producer_1.samples_out", "b/Consumer_1.samples_in", "--id", "cross",
                  "--qos", "reliability=besteffort", "--qos", "depth=4"});
  INFO(out);
  REQUIRE(rc == 0);
  CHECK(TestDomain::wait_for([&] { return delivered(domain, "cross") > 10; }));
  const Json cross = runtime_connection(domain, "cross");
  CHECK(cross.at("qos").at("reliability") == "besteffort");
  CHECK(cross.at("qos").at("depth") == 4);

  // Checked before anything is made.
  auto [trc, tout] = domain.cli({"connect", "a/Producer_1.events_out", "b/Consumer_1.samples_in"});
  CHECK(trc == 1);
  CHECK_THAT(tout,
             Catch::Contains("port type: a/Producer_1.events_out sends IDL:rsca/PropertyEvent:1.0, "
                             "but b/Consumer_1.samples_in takes IDL:rsca/SampleSeq:1.0"));
  auto [prc, pout] = domain.cli({"connect", "a/Producer_1.samples_out", "b/Consumer_1.nope"});
  CHECK(prc == 3);
  CHECK_THAT(pout, Catch::Contains("b/Consumer_1.nope is not a provides port"));

  // Removed while data flows: b's consumer keeps only its own connection.
  auto [drc, dout] = domain.cli({"disconnect", "cross"});
  REQUIRE(drc == 0);
  CHECK(runtime_connection(domain, "cross").is_null());
  auto b_status = [&] {
    auto app = domain.call("app.show", Json{{"app", "b"}});
    for (const auto &c : app->at("components"))
      if (c.at("id") == "Consumer_1")
        return domain.client().call_sync(c.at("address"), "component.status", Json::object(), 5s);
    return rsca::control::CallResult<Json>(
        rsca::control::call_error(rsca::control::Status::NotFound, ""));
  };
  auto status = b_status();
  REQUIRE(status.has_value());
  for (const auto &port : status->at("ports"))
    if (port.at("name") == "samples_in")
      CHECK(port.at("connections").size() == 1);

  // A connection outlives its applications: with one released it waits for it again, and the
  // other end is disconnected.
  REQUIRE(
      domain
          .cli({"connect", "a/Producer_1.samples_out", "b/Consumer_1.samples_in", "--id", "again"})
          .first == 0);
  REQUIRE(domain.call("app.release", Json{{"app", "a"}}).has_value());
  const Json again = runtime_connection(domain, "again");
  CHECK(again.at("state") == "pending");
  CHECK(again.at("waiting_for") == "a is gone");
  status = b_status();
  REQUIRE(status.has_value());
  for (const auto &port : status->at("ports"))
    if (port.at("name") == "samples_in")
      CHECK(port.at("connections").size() == 1);
  REQUIRE(domain.cli({"disconnect", "again"}).first == 0);
  CHECK(runtime_connection(domain, "again").is_null());
  REQUIRE(domain.call("app.release", Json{{"app", "b"}}).has_value());
  domain.require_clean(pids);
}

TEST_CASE("a runtime connection outlasts a restart of the domain daemon until disconnected",
          "[integration][connections]") {
  TestDomain domain;
  const auto sad =
      (kSource / "profiles/dom/waveforms/ProducerConsumer/ProducerConsumer.sad.xml").string();
  REQUIRE(domain.cli({"install", sad}).first == 0);
  // Made while neither application runs: pending, and kept by the domain. Its id is the first
  // the domain gives (runtime_1).
  auto [rc, out] = domain.cli({"--json", "connect", "a/Producer_1.samples_out",
                               "b/Consumer_1.samples_in", "--qos", "depth=4"});
  INFO(out);
  REQUIRE(rc == 0);
  CHECK_THAT(out, Catch::Contains("\"persisted\": true"));
  auto restart = [&] {
    domain.restart_domaind();
    REQUIRE(TestDomain::wait_for([&] {
      auto nodes = domain.call("domain.nodes", Json::object(), 2s);
      return nodes && nodes->at("nodes").size() == 2;
    }));
  };
  restart();
  const Json kept = runtime_connection(domain, "runtime_1");
  REQUIRE_FALSE(kept.is_null());
  CHECK(kept.at("state") == "pending");
  CHECK(kept.at("qos").at("depth") == 4);
  // A new connection does not take the restored one's id, which a restarted counter would give.
  auto [nrc, nout] = domain.cli({"connect", "a/Producer_1.samples_out", "b/Consumer_1.samples_in"});
  INFO(nout);
  REQUIRE(nrc == 0);
  CHECK_FALSE(runtime_connection(domain, "runtime_2").is_null());
  // Completed when its applications come, carrying data.
  for (const char *name : {"a", "b"})
    REQUIRE(domain.cli({"launch", "ProducerConsumer", "--name", name}).first == 0);
  CHECK(TestDomain::wait_for([&] { return delivered(domain, "runtime_1") > 10; }));
  const std::vector<long> pids = pids_of_applications(domain, {"a", "b"});
  // Disconnected, it stays gone after the next restart.
  auto made = domain.call("connection.list");
  REQUIRE(made.has_value());
  int runtime = 0;
  for (const auto &c : made->at("connections")) {
    if (c.at("application") != "(runtime)")
      continue;
    ++runtime;
    REQUIRE(domain.cli({"disconnect", c.at("id").get<std::string>()}).first == 0);
  }
  CHECK(runtime == 2);
  for (const char *name : {"a", "b"})
    REQUIRE(domain.call("app.release", Json{{"app", name}}).has_value());
  domain.require_clean(pids);
  restart();
  CHECK(runtime_connection(domain, "runtime_1").is_null());
  auto list = domain.call("connection.list");
  REQUIRE(list.has_value());
  for (const auto &c : list->at("connections"))
    CHECK(c.at("application") != "(runtime)"); // no runtime connection came back
}

TEST_CASE("a uses port of CF::Resource connected to a component's supported interface calls it",
          "[integration][connections]") {
  // componentsupportedinterface: Supervisor_1's port "managed" holds Producer_1's control
  // address; once started, Supervisor_1 configures Producer_1 through it and reads back.
  TestDomain domain;
  domain.install("Supervised");
  auto [rc, out] = domain.cli({"launch", "Supervised"});
  INFO(out);
  REQUIRE(rc == 0);
  auto query = [&](const std::string &component, const std::string &id) {
    auto q = domain.call("app.query",
                         Json{{"app", "Supervised"}, {"component", component}, {"ids", {id}}});
    return q ? q->at("properties").at(id) : Json();
  };
  CHECK(TestDomain::wait_for([&] { return query("Supervisor_1", "supervised") == 1; }));
  CHECK(query("Supervisor_1", "confirmed_message") == "set by Supervisor_1");
  CHECK(query("Producer_1", "message") == "set by Supervisor_1");
  // The connection, its kind and the calls made through it.
  auto [lrc, listed] = domain.cli({"ls", "connections", "Supervised"});
  INFO(listed);
  CHECK(lrc == 0);
  CHECK_THAT(listed, Catch::Contains("Supervised/supervision: Supervisor_1.managed -> Producer_1  "
                                     "[calls IDL:CF/Resource:1.0]"));
  CHECK_THAT(listed, Catch::Contains("uses: 2 calls")); // the configure and the query
  auto app = domain.call("app.show", Json{{"app", "Supervised"}});
  REQUIRE(app.has_value());
  REQUIRE(domain.call("app.release", Json{{"app", "Supervised"}}).has_value());
  domain.require_clean(pids_of(*app));
}

TEST_CASE("a connection rsca cannot make is refused before anything runs, not left out",
          "[integration][connections][failure]") {
  using Case = std::pair<std::string, std::string>;
  const auto [name, message] =
      GENERATE(Case{"FoundByName", "connection elsewhere: only event channels can be found by "
                                   "findby; \"Elsewhere\" is not one"},
               Case{"SupervisedByData",
                    "connection \"supervision\": uses port Producer_1.samples_out is of "
                    "IDL:rsca/SampleSeq:1.0, which cannot call a component's supported interface"},
               Case{"SupervisesItself",
                    "connection \"supervision\": component \"Supervisor_1\" cannot call its own "
                    "supported interface"},
               Case{"SupervisesChannel", "connection supervision: a supported interface connects a "
                                         "component's uses port to another component"});
  TestDomain domain;
  domain.install(name);
  auto [rc, out] = domain.cli({"launch", name});
  INFO(out);
  CHECK(rc == 1);
  CHECK_THAT(out, Catch::Contains("failed at step 'check'"));
  CHECK_THAT(out, Catch::Contains(message));
  domain.require_clean({});
}
