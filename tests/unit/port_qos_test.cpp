// Connection QoS as component.connect carries it: defaults, the round trip through JSON, and the
// DDS QoS it builds (read back with dds_qget_*).
#include "dds/port_qos.hpp"

#include <catch2/catch.hpp>

#include "profile/profile_loader.hpp"

using namespace rsca;
using namespace std::chrono_literals;
using Json = nlohmann::json;
using profile::ConnectionQos;

namespace {

Duration duration(std::chrono::nanoseconds value) {
  return Duration{value};
}

dds::Qos qos_of(const Json &json) {
  INFO("QoS " << json.dump());
  auto qos = dds::qos_from_json(json);
  if (!qos)
    FAIL("unexpected error: " << qos.error().to_string());
  return std::move(*qos);
}

std::string error_of(const Json &json) {
  INFO("QoS " << json.dump());
  auto qos = dds::qos_from_json(json);
  REQUIRE_FALSE(qos.has_value());
  return qos.error().diagnostics().at(0).message;
}

} // namespace

TEST_CASE("a connection without QoS gets the documented defaults", "[port_qos]") {
  const Json expected = {{"reliability", "reliable"},
                         {"durability", "volatile"},
                         {"history", "keeplast"},
                         {"depth", 16},
                         {"deadline_ns", "infinite"},
                         {"latencybudget_ns", 0},
                         {"transportpriority", 0},
                         {"liveliness", "automatic"},
                         {"lease_ns", "infinite"},
                         {"ownership", "shared"},
                         {"strength", 0},
                         {"transport", "node"}};
  CHECK(dds::qos_to_json(ConnectionQos{}) == expected);
  auto parsed = dds::connection_qos_from_json(Json::object());
  REQUIRE(parsed.has_value());
  CHECK(dds::qos_to_json(*parsed) == expected);
}

TEST_CASE("every QoS field survives the round trip through JSON", "[port_qos]") {
  ConnectionQos qos;
  qos.reliability = profile::Reliability::BestEffort;
  qos.durability = profile::Durability::TransientLocal;
  qos.history = profile::History::KeepLast;
  qos.depth = 4;
  qos.deadline = duration(100ms);
  qos.latency_budget = duration(5ms);
  qos.transport_priority = -3;
  qos.liveliness = profile::Liveliness::ManualByTopic;
  qos.lease = duration(2s);
  qos.ownership = profile::Ownership::Exclusive;
  qos.strength = 7;
  const Json json = dds::qos_to_json(qos);
  CHECK(json.at("deadline_ns") == 100'000'000);
  CHECK(json.at("liveliness") == "manualbytopic");
  auto back = dds::connection_qos_from_json(json);
  REQUIRE(back.has_value());
  CHECK(back->reliability == qos.reliability);
  CHECK(back->durability == qos.durability);
  CHECK(back->history == qos.history);
  CHECK(back->depth == qos.depth);
  CHECK(back->deadline == qos.deadline);
  CHECK(back->latency_budget == qos.latency_budget);
  CHECK(back->transport_priority == qos.transport_priority);
  CHECK(back->liveliness == qos.liveliness);
  CHECK(back->lease == qos.lease);
  CHECK(back->ownership == qos.ownership);
  CHECK(back->strength == qos.strength);

  ConnectionQos keep_all;
  keep_all.history = profile::History::KeepAll;
  CHECK_FALSE(dds::qos_to_json(keep_all).contains("depth"));
}

TEST_CASE("the QoS built from JSON is the one DDS gets", "[port_qos]") {
  const auto qos = qos_of({{"reliability", "besteffort"},
                           {"durability", "transientlocal"},
                           {"history", "keeplast"},
                           {"depth", 4},
                           {"deadline_ns", 100'000'000},
                           {"latencybudget_ns", 5'000'000},
                           {"transportpriority", 9},
                           {"liveliness", "manualbyparticipant"},
                           {"lease_ns", 2'000'000'000},
                           {"ownership", "exclusive"},
                           {"strength", 7}});
  dds_reliability_kind_t reliability{};
  dds_duration_t blocking = 0;
  REQUIRE(dds_qget_reliability(qos.get(), &reliability, &blocking));
  CHECK(reliability == DDS_RELIABILITY_BEST_EFFORT);
  dds_durability_kind_t durability{};
  REQUIRE(dds_qget_durability(qos.get(), &durability));
  CHECK(durability == DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_history_kind_t history{};
  int32_t depth = 0;
  REQUIRE(dds_qget_history(qos.get(), &history, &depth));
  CHECK(history == DDS_HISTORY_KEEP_LAST);
  CHECK(depth == 4);
  dds_duration_t deadline = 0;
  REQUIRE(dds_qget_deadline(qos.get(), &deadline));
  CHECK(deadline == DDS_MSECS(100));
  dds_duration_t budget = 0;
  REQUIRE(dds_qget_latency_budget(qos.get(), &budget));
  CHECK(budget == DDS_MSECS(5));
  int32_t priority = 0;
  REQUIRE(dds_qget_transport_priority(qos.get(), &priority));
  CHECK(priority == 9);
  dds_liveliness_kind_t liveliness{};
  dds_duration_t lease = 0;
  REQUIRE(dds_qget_liveliness(qos.get(), &liveliness, &lease));
  CHECK(liveliness == DDS_LIVELINESS_MANUAL_BY_PARTICIPANT);
  CHECK(lease == DDS_SECS(2));
  dds_ownership_kind_t ownership{};
  REQUIRE(dds_qget_ownership(qos.get(), &ownership));
  CHECK(ownership == DDS_OWNERSHIP_EXCLUSIVE);
  int32_t strength = 0;
  REQUIRE(dds_qget_ownership_strength(qos.get(), &strength));
  CHECK(strength == 7);
}

TEST_CASE("the default QoS in DDS terms", "[port_qos]") {
  const auto qos = qos_of(Json::object());
  dds_reliability_kind_t reliability{};
  dds_duration_t blocking = 0;
  REQUIRE(dds_qget_reliability(qos.get(), &reliability, &blocking));
  CHECK(reliability == DDS_RELIABILITY_RELIABLE);
  CHECK(blocking > 0);
  CHECK(blocking != DDS_INFINITY); // a full reliable writer never blocks forever
  dds_history_kind_t history{};
  int32_t depth = 0;
  REQUIRE(dds_qget_history(qos.get(), &history, &depth));
  CHECK(history == DDS_HISTORY_KEEP_LAST);
  CHECK(depth == 16);
  dds_duration_t deadline = 0;
  REQUIRE(dds_qget_deadline(qos.get(), &deadline));
  CHECK(deadline == DDS_INFINITY);
  dds_liveliness_kind_t liveliness{};
  dds_duration_t lease = 0;
  REQUIRE(dds_qget_liveliness(qos.get(), &liveliness, &lease));
  CHECK(liveliness == DDS_LIVELINESS_AUTOMATIC);
  CHECK(lease == DDS_INFINITY);
  dds_ownership_kind_t ownership{};
  REQUIRE(dds_qget_ownership(qos.get(), &ownership));
  CHECK(ownership == DDS_OWNERSHIP_SHARED);

  const auto keep_all = qos_of({{"history", "keepall"}});
  REQUIRE(dds_qget_history(keep_all.get(), &history, &depth));
  CHECK(history == DDS_HISTORY_KEEP_ALL);
}

TEST_CASE("bad QoS JSON is refused, naming the key", "[port_qos]") {
  CHECK(error_of({{"reliable", true}}) == "unknown QoS \"reliable\"");
  CHECK(error_of({{"reliability", "sometimes"}}) ==
        "\"reliability\" is \"sometimes\", not one of besteffort, reliable");
  CHECK(error_of({{"depth", 0}}) == "\"depth\" is 0, not an integer from 1 to 2147483647");
  // As received: numbers >= 0 parse as unsigned.
  CHECK(error_of(Json::parse(R"({"depth": 0})")) ==
        "\"depth\" is 0, not an integer from 1 to 2147483647");
  CHECK(error_of(Json::parse(R"({"strength": 2147483648})")) ==
        "\"strength\" is 2147483648, not an integer from -2147483648 to 2147483647");
  CHECK(error_of({{"strength", "high"}}) ==
        "\"strength\" is \"high\", not an integer from -2147483648 to 2147483647");
  CHECK(error_of({{"deadline_ns", -1}}) ==
        "\"deadline_ns\" is -1, not whole nanoseconds or \"infinite\"");
  CHECK(error_of({{"lease_ns", 1.5}}) ==
        "\"lease_ns\" is 1.5, not whole nanoseconds or \"infinite\"");
  CHECK(error_of(Json::array()) == "the QoS is [], not an object");
}

TEST_CASE("the ProducerConsumer SAD's connection QoS as the domain sends it", "[port_qos]") {
  profile::ProfileLoader loader;
  auto app = loader.load_application(
      RSCA_SOURCE_DIR "/profiles/dom/waveforms/ProducerConsumer/ProducerConsumer.sad.xml");
  REQUIRE(app.has_value());
  REQUIRE_FALSE(app->sad->connections.empty());
  const auto &qos = app->sad->connections.front().qos;
  REQUIRE(qos.has_value());
  const Json json = dds::qos_to_json(*qos);
  CHECK(json.at("reliability") == "reliable");
  CHECK(json.at("depth") == 16);
  CHECK(json.at("deadline_ns") == 100'000'000);
  CHECK(json.at("lease_ns") == "infinite"); // a default filled in
  CHECK(dds::qos_from_json(json).has_value());
}
