// The component runtime with real processes: rsca-producer and rsca-consumer started as the GPP
// would start them, driven over the control plane from a test endpoint on a DDS domain of the
// test's own.
#include <condition_variable>
#include <map>
#include <mutex>
#include <set>

#include <catch2/catch.hpp>

#include "../unit/test_domain.hpp"
#include "child_process.hpp"
#include "control/endpoint.hpp"
#include "dds/port_qos.hpp"

using namespace rsca;
using namespace std::chrono_literals;
using control::CallResult;
using control::Json;
using control::Status;
using test::ChildProcess;

namespace {

constexpr auto kCallTimeout = 5s;
constexpr auto kStartBound = 20s; // process start, profile load and DDS discovery
constexpr auto kExitBound = 10s;
constexpr auto kStreamBound = 15s;

const std::string kSampleSeq = "IDL:rsca/SampleSeq:1.0";

// The latest announcement of every endpoint the test endpoint follows.
class Announcements {
public:
  void on_event(const control::AnnouncementEvent &event) {
    std::lock_guard lock(mutex_);
    if (event.kind == control::AnnouncementEvent::Kind::Gone) {
      alive_.erase(event.address);
      gone_.insert(event.address);
    } else {
      alive_[event.address] = event;
      gone_.erase(event.address);
    }
    changed_.notify_all();
  }

  // The announcement of `address` once it satisfies `accept`, or nothing after `timeout`.
  template <typename Accept>
  std::optional<control::AnnouncementEvent>
  wait_alive(const std::string &address, std::chrono::milliseconds timeout, Accept accept) {
    std::unique_lock lock(mutex_);
    const bool seen = changed_.wait_for(lock, timeout, [&] {
      auto it = alive_.find(address);
      return it != alive_.end() && accept(it->second);
    });
    if (!seen)
      return std::nullopt;
    return alive_.at(address);
  }

  bool wait_gone(const std::string &address, std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, timeout, [&] { return gone_.count(address) > 0; });
  }

private:
  std::mutex mutex_;
  std::condition_variable changed_;
  std::map<std::string, control::AnnouncementEvent> alive_;
  std::set<std::string> gone_;
};

// A component process and its control address.
struct ComponentProcess {
  std::string address;
  std::unique_ptr<ChildProcess> process;
};

class Harness {
public:
  Harness()
      : participant_(test::participant()), announcements_(std::make_shared<Announcements>()),
        application_("app" + std::to_string(::getpid())) {
    auto endpoint = control::Endpoint::open(
        participant_, "rsca/cli/test-" + std::to_string(::getpid()),
        {.workers = 2,
         .senders = 4,
         .on_announcement = [events = announcements_](const auto &e) { events->on_event(e); },
         .aliases = {},
         .prepare_kinds = {}});
    REQUIRE(endpoint.has_value());
    endpoint_ = std::move(*endpoint);
  }

  // Starts the component `binary` (in the build's bin directory) as instance `instance`, with the
  // SPD of profiles/dom/components/<component>/.
  ComponentProcess spawn(const std::string &binary, const std::string &component,
                         const std::string &instance, std::vector<std::string> extra = {}) {
    const std::string address = "rsca/component/" + application_ + "/" + instance;
    const std::string spd = std::string(RSCA_SOURCE_DIR) + "/profiles/dom/components/" + component +
                            "/" + component + ".spd.xml";
    std::vector<std::string> args{"COMPONENT_IDENTIFIER", instance + ":" + application_,
                                  "NAME_BINDING",         instance,
                                  "PROFILE_NAME",         spd,
                                  "DOMAIN_NAME",          "rsca",
                                  "APPLICATION",          application_,
                                  "CONTROL_ADDRESS",      address};
    args.insert(args.end(), extra.begin(), extra.end());
    return {address, std::make_unique<ChildProcess>(std::string(RSCA_BIN_DIR) + "/" + binary, args,
                                                    test::isolated_settings().environment())};
  }

  // Waits for the component's registration (its first announcement).
  Json registration(const ComponentProcess &component) {
    auto event = announcements_->wait_alive(component.address, kStartBound,
                                            [](const auto &) { return true; });
    if (!event)
      FAIL("no announcement from " << component.address << " within the bound ("
                                   << ChildProcess::describe(component.process->wait_exit(0ms))
                                   << ")");
    CHECK(event->endpoint_kind == "component");
    return event->body;
  }

  Json announced_state(const ComponentProcess &component, const std::string &state) {
    auto event = announcements_->wait_alive(component.address, kCallTimeout, [&](const auto &e) {
      return e.body.value("state", "") == state;
    });
    REQUIRE(event.has_value());
    return event->body;
  }

  CallResult<Json> call(const ComponentProcess &component, const std::string &operation,
                        Json body = Json::object()) {
    return endpoint_->call_sync(component.address, operation, std::move(body), kCallTimeout);
  }

  // The reply of a call that must succeed.
  Json ok(const ComponentProcess &component, const std::string &operation,
          Json body = Json::object()) {
    INFO(operation << " " << body.dump() << " on " << component.address);
    auto reply = call(component, operation, std::move(body));
    if (!reply)
      FAIL(control::to_string(reply.error().status) << ": " << reply.error().message);
    return *reply;
  }

  // The error of a call that must fail.
  control::CallError error(const ComponentProcess &component, const std::string &operation,
                           Json body) {
    INFO(operation << " " << body.dump() << " on " << component.address);
    auto reply = call(component, operation, std::move(body));
    REQUIRE_FALSE(reply.has_value());
    return reply.error();
  }

  Json query(const ComponentProcess &component, const std::string &id) {
    return ok(component, "component.query", {{"ids", {id}}}).at("properties").at(id);
  }

  // The status of `port`'s connection `connection`, or null when the port has none of that id.
  Json connection_status(const ComponentProcess &component, const std::string &port,
                         const std::string &connection) {
    const Json status = ok(component, "component.status");
    for (const auto &p : status.at("ports"))
      if (p.at("name") == port)
        for (const auto &c : p.at("connections"))
          if (c.at("connection") == connection)
            return c;
    return nullptr;
  }

  // Asks until `done` holds for the answer of `ask` or the bound passes; each ask is one
  // bounded control call, so the component's own pace sets the polling rate.
  template <typename Ask, typename Done>
  bool eventually(std::chrono::milliseconds bound, Ask ask, Done done) {
    const auto deadline = std::chrono::steady_clock::now() + bound;
    while (std::chrono::steady_clock::now() < deadline)
      if (done(ask()))
        return true;
    return false;
  }

  bool gone(const ComponentProcess &component) {
    return announcements_->wait_gone(component.address, kExitBound);
  }

  const std::string &application() const { return application_; }

private:
  std::shared_ptr<dds::Participant> participant_;
  std::shared_ptr<Announcements> announcements_;
  std::string application_;
  std::unique_ptr<control::Endpoint> endpoint_;
};

Json connect_body(const std::string &port, const std::string &direction, const std::string &topic) {
  profile::ConnectionQos qos;
  qos.reliability = profile::Reliability::Reliable;
  return {{"connection", "samples"}, {"port", port},        {"direction", direction},
          {"topic", topic},          {"repid", kSampleSeq}, {"qos", dds::qos_to_json(qos)}};
}

void check_exit_ok(ChildProcess &process) {
  const auto status = process.wait_exit(kExitBound);
  INFO("the process ended with " << ChildProcess::describe(status));
  REQUIRE(status.has_value());
  CHECK(WIFEXITED(*status));
  CHECK(WEXITSTATUS(*status) == 0);
}

} // namespace

TEST_CASE("a component registers by announcing its id, pid, state and ports", "[component]") {
  Harness h;
  auto producer = h.spawn("rsca-producer", "Producer", "Producer_1");
  const Json body = h.registration(producer);
  CHECK(body.at("id") == "Producer_1:" + h.application());
  CHECK(body.at("application") == h.application());
  CHECK(body.at("pid") == producer.process->pid());
  CHECK(body.at("state") == "loaded");
  const Json samples = {{"name", "samples_out"}, {"direction", "uses"}, {"repid", kSampleSeq}};
  const Json events = {
      {"name", "events_out"}, {"direction", "uses"}, {"repid", "IDL:rsca/PropertyEvent:1.0"}};
  CHECK(body.at("ports") == Json::array({samples, events}));
}

TEST_CASE("configure checks every value against the PRF and applies all or nothing",
          "[component]") {
  Harness h;
  auto producer = h.spawn("rsca-producer", "Producer", "Producer_1");
  auto consumer = h.spawn("rsca-consumer", "Consumer", "Consumer_1");
  h.registration(producer);
  h.registration(consumer);
  h.ok(producer, "component.initialize");

  // The PRF defaults, before any configure.
  CHECK(h.query(producer, "rate_hz") == 100.0);
  CHECK(h.query(producer, "stream") == Json{{"stream_id", "producer"}, {"sample_rate", 1000.0}});

  h.ok(producer, "component.configure",
       {{"properties",
         {{"rate_hz", 250.5}, {"message", "hi"}, {"stream", {{"stream_id", "imu"}}}}}});
  const Json all = h.ok(producer, "component.query", {{"ids", Json::array()}}).at("properties");
  CHECK(all.at("rate_hz") == 250.5);
  CHECK(all.at("message") == "hi");
  CHECK(all.at("payload_size") == 64);
  CHECK(all.at("stream") ==
        Json{{"stream_id", "imu"}, {"sample_rate", 1000.0}}); // a partial update

  auto refused = [&](const ComponentProcess &component, const Json &properties) {
    const auto error = h.error(component, "component.configure", {{"properties", properties}});
    CHECK(error.status == Status::BadRequest);
    return error.message;
  };
  // A bad value next to a good one: neither is applied.
  CHECK_THAT(refused(producer, {{"payload_size", 8}, {"rate_hz", "fast"}}),
             Catch::Contains("property \"rate_hz\": \"fast\" is not a double"));
  CHECK_THAT(refused(producer, {{"payload_size", 8}, {"nope", 1}}),
             Catch::Contains("unknown property \"nope\""));
  CHECK_THAT(refused(producer, {{"payload_size", 8}, {"rate_hz", 1e9}}),
             Catch::Contains("property \"rate_hz\": 1000000000.0 is outside its range 0.1..10000"));
  CHECK_THAT(refused(producer, {{"payload_size", -8}}),
             Catch::Contains("property \"payload_size\": -8 is out of range for ulong"));
  CHECK_THAT(refused(producer, {{"stream", {{"rate", 1}}}}),
             Catch::Contains("struct \"stream\" has no member \"rate\""));
  CHECK_THAT(refused(consumer, {{"log_every", 5}, {"received", 5}}),
             Catch::Contains("property \"received\" is read-only"));
  CHECK(h.query(producer, "payload_size") == 64);
  CHECK(h.query(producer, "rate_hz") == 250.5);
  CHECK(h.query(consumer, "log_every") == 0);

  CHECK(h.error(producer, "component.query", {{"ids", {"nope"}}}).status == Status::BadRequest);
  CHECK(h.error(producer, "component.configure", {{"props", 1}}).status == Status::BadRequest);
}

TEST_CASE("a producer streams to a consumer over a connection the domain makes", "[component]") {
  Harness h;
  auto producer = h.spawn("rsca-producer", "Producer", "Producer_1", {"payload_size", "32"});
  auto consumer = h.spawn("rsca-consumer", "Consumer", "Consumer_1");
  h.registration(producer);
  h.registration(consumer);
  CHECK(h.error(consumer, "component.start", Json::object()).status == Status::Rejected);
  for (const auto *c : {&producer, &consumer}) {
    h.ok(*c, "component.initialize");
    h.announced_state(*c, "initialized");
  }
  CHECK(h.query(producer, "payload_size") == 32); // an execparam on the command line
  h.ok(producer, "component.configure", {{"properties", {{"rate_hz", 200.0}}}});
  h.ok(consumer, "component.configure", {{"properties", {{"log_every", 50}}}});

  const std::string topic = "rsca_test_samples_" + std::to_string(::getpid());
  SECTION("connect refuses a port that does not fit") {
    CHECK(h.error(producer, "component.connect", connect_body("samples_in", "provides", topic))
              .status == Status::NotFound);
    CHECK(h.error(producer, "component.connect", connect_body("samples_out", "provides", topic))
              .status == Status::BadRequest);
    auto wrong_type = connect_body("samples_out", "uses", topic);
    wrong_type["repid"] = "IDL:rsca/Command:1.0";
    CHECK(h.error(producer, "component.connect", wrong_type).status == Status::BadRequest);
    auto bad_qos = connect_body("samples_out", "uses", topic);
    bad_qos["qos"]["depth"] = 0;
    CHECK_THAT(h.error(producer, "component.connect", bad_qos).message,
               Catch::Contains("\"depth\""));
  }
  SECTION("samples flow while connected and started, and stop matching when disconnected") {
    h.ok(producer, "component.connect", connect_body("samples_out", "uses", topic));
    h.ok(consumer, "component.connect", connect_body("samples_in", "provides", topic));
    h.ok(consumer, "component.start");
    h.ok(producer, "component.start");
    h.announced_state(producer, "started");

    const bool streamed = h.eventually(
        kStreamBound, [&] { return h.query(consumer, "received"); },
        [](const Json &received) { return received.get<std::uint64_t>() > 20; });
    REQUIRE(streamed);
    CHECK(h.query(consumer, "last_latency_us").get<double>() > 0);

    const Json sent = h.connection_status(producer, "samples_out", "samples");
    REQUIRE(sent.is_object());
    CHECK(sent.at("topic") == topic);
    CHECK(sent.at("matched") == 1);
    CHECK(sent.at("samples").get<std::uint64_t>() > 20);
    const Json got = h.connection_status(consumer, "samples_in", "samples");
    REQUIRE(got.is_object());
    CHECK(got.at("matched") == 1);
    CHECK(got.at("samples").get<std::uint64_t>() > 20);
    CHECK(h.ok(consumer, "component.status").at("state") == "started");

    h.ok(consumer, "component.disconnect", {{"connection", "samples"}, {"port", "samples_in"}});
    CHECK(h.connection_status(consumer, "samples_in", "samples").is_null());
    CHECK(h.error(consumer, "component.disconnect",
                  {{"connection", "samples"}, {"port", "samples_in"}})
              .status == Status::NotFound);
    const bool unmatched = h.eventually(
        kStreamBound, [&] { return h.connection_status(producer, "samples_out", "samples"); },
        [](const Json &status) { return status.at("matched") == 0; });
    CHECK(unmatched);

    h.ok(producer, "component.stop");
    CHECK(h.ok(producer, "component.status").at("state") == "stopped");
  }

  for (auto *c : {&producer, &consumer}) {
    h.ok(*c, "component.release");
    check_exit_ok(*c->process);
    CHECK(h.gone(*c));
  }
}

TEST_CASE("SIGTERM and SIGINT make a component exit cleanly", "[component]") {
  Harness h;
  auto consumer = h.spawn("rsca-consumer", "Consumer", "Consumer_1");
  auto producer = h.spawn("rsca-producer", "Producer", "Producer_1");
  h.registration(consumer);
  h.registration(producer);
  h.ok(producer, "component.initialize");
  h.ok(producer, "component.start"); // its service thread is running when the signal comes
  consumer.process->signal(SIGTERM);
  producer.process->signal(SIGINT);
  check_exit_ok(*consumer.process);
  check_exit_ok(*producer.process);
  CHECK(h.gone(consumer));
  CHECK(h.gone(producer));
}

TEST_CASE("a component refuses wrong exec parameters and profiles", "[component]") {
  Harness h;
  const auto settings = test::isolated_settings().environment();
  SECTION("a missing exec parameter is a usage error") {
    ChildProcess process(RSCA_BIN_DIR "/rsca-consumer", {"COMPONENT_IDENTIFIER", "c"}, settings);
    const auto status = process.wait_exit(kExitBound);
    REQUIRE(status.has_value());
    CHECK(WEXITSTATUS(*status) == 2);
  }
  SECTION("a profile whose ports do not fit the component") {
    // The consumer's executable with the producer's SPD: samples_in is not in that SCD.
    auto wrong = h.spawn("rsca-consumer", "Producer", "Wrong_1");
    const auto status = wrong.process->wait_exit(kExitBound);
    REQUIRE(status.has_value());
    CHECK(WEXITSTATUS(*status) == 3);
  }
  SECTION("an execparam value that does not fit its property") {
    auto bad = h.spawn("rsca-producer", "Producer", "Bad_1", {"rate_hz", "fast"});
    const auto status = bad.process->wait_exit(kExitBound);
    REQUIRE(status.has_value());
    CHECK(WEXITSTATUS(*status) == 3);
  }
}
