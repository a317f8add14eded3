// Unit tests of the one parser of connection QoS values (profile/connection_qos.hpp): the SAD's
// <qos> and the QoS of rsca connect (dds::connection_qos_from_json) take the same names and
// values (issue 18, defect 11: "deadline=100ms" was an unknown QoS for rsca connect).
#include "dds/port_qos.hpp"
#include "profile/connection_qos.hpp"

#include <string>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

using namespace rsca;
using Json = nlohmann::json;
using profile::ConnectionQos;

namespace {

ConnectionQos from_json(const Json &json) {
  auto qos = dds::connection_qos_from_json(json);
  if (!qos)
    FAIL("unexpected error: " << qos.error().to_string());
  return *qos;
}

std::string qos_error(const Json &json) {
  auto qos = dds::connection_qos_from_json(json);
  REQUIRE_FALSE(qos.has_value());
  return qos.error().diagnostics().at(0).message;
}

} // namespace

TEST_CASE("connection QoS: every SAD attribute, as text, means the same to rsca connect",
          "[connection_qos]") {
  // Each attribute as a SAD would give it, and what it must set.
  const Json sad = {{"reliability", "besteffort"},
                    {"durability", "transientlocal"},
                    {"history", "keeplast"},
                    {"depth", "4"},
                    {"deadline", "100ms"},
                    {"latencybudget", "250us"},
                    {"transportpriority", "-2"},
                    {"liveliness", "manualbyparticipant"},
                    {"lease", "1.5s"},
                    {"ownership", "exclusive"},
                    {"strength", "7"},
                    {"transport", "direct"}};
  REQUIRE(sad.size() == profile::kQosAttributes.size());
  ConnectionQos by_sad_parser;
  for (const auto &[name, text] : sad.items()) {
    INFO(name);
    REQUIRE(profile::set_qos_attribute(by_sad_parser, name, text.get<std::string>()).has_value());
  }
  const ConnectionQos by_json = from_json(sad);
  CHECK(dds::qos_to_json(by_json) == dds::qos_to_json(by_sad_parser));
  const Json wire = dds::qos_to_json(by_json);
  CHECK(wire.at("deadline_ns") == 100'000'000);
  CHECK(wire.at("latencybudget_ns") == 250'000);
  CHECK(wire.at("lease_ns") == 1'500'000'000);
  CHECK(wire.at("transportpriority") == -2);
  CHECK(wire.at("depth") == 4);
  CHECK(wire.at("reliability") == "besteffort");
  CHECK(wire.at("transport") == "direct");
}

TEST_CASE("connection QoS: the wire's form reads back as it was written", "[connection_qos]") {
  const Json wire = dds::qos_to_json(from_json({{"deadline", "infinite"}, {"depth", 8}}));
  CHECK(wire.at("deadline_ns") == "infinite");
  CHECK(dds::qos_to_json(from_json(wire)) == wire);
}

TEST_CASE("connection QoS: values the SAD refuses are refused, quoting an excerpt",
          "[connection_qos]") {
  CHECK(qos_error({{"deadline", 100}}) ==
        "\"deadline\" is 100, not a duration such as 100ms, 1.5s or infinite (units ns, us, ms, "
        "s; at most about 292 years)");
  CHECK(qos_error({{"depth", "0"}}) == "\"depth\" is \"0\", not an integer from 1 to 2147483647");
  CHECK(qos_error({{"transport", "udp"}}) ==
        "\"transport\" is \"udp\", not one of node, direct, tcp");
  CHECK(qos_error({{"depth", "4x"}}) == "\"depth\" is \"4x\", not an integer from 1 to 2147483647");
  CHECK(qos_error({{"deadline", "100ms"}, {"deadline_ns", 5}}) ==
        "give \"deadline\" or \"deadline_ns\", not both");
  const std::string huge(100 * 1024, 'x');
  const std::string bad_value = qos_error({{"lease", huge}});
  CHECK_THAT(bad_value, Catch::StartsWith("\"lease\" is \"xxxx"));
  CHECK(bad_value.size() < 300);
  const std::string bad_key = qos_error({{huge, 1}});
  CHECK_THAT(bad_key, Catch::StartsWith("unknown QoS \"xxxx"));
  CHECK(bad_key.size() < 100);
}

TEST_CASE("connection QoS: inconsistent values are named", "[connection_qos]") {
  ConnectionQos qos;
  CHECK_FALSE(profile::qos_inconsistency(qos).has_value());
  REQUIRE(profile::set_qos_attribute(qos, "history", "keepall").has_value());
  REQUIRE(profile::set_qos_attribute(qos, "depth", "3").has_value());
  CHECK(profile::qos_inconsistency(qos) ==
        "depth applies only to history=\"keeplast\", not to keepall");
  CHECK_FALSE(profile::set_qos_attribute(qos, "nope", "1").has_value());
}

TEST_CASE("connection QoS: each transport honours what its table says, and a connection that "
          "names none gets one that honours its QoS",
          "[connection_qos][qos]") {
  using profile::Transport;
  auto qos_of = [](std::initializer_list<std::pair<const char *, const char *>> attributes) {
    ConnectionQos qos;
    for (auto [name, text] : attributes)
      REQUIRE(profile::set_qos_attribute(qos, name, text).has_value());
    return qos;
  };
  // The defaults, transient-local and best-effort keep-all travel through the nodes.
  for (const auto &qos : {qos_of({}), qos_of({{"durability", "transientlocal"}}),
                          qos_of({{"reliability", "besteffort"}, {"history", "keepall"}})}) {
    CHECK(profile::transport_for(qos) == Transport::Node);
    CHECK_FALSE(profile::not_honoured(qos, Transport::Node).has_value());
    CHECK(dds::connection_qos_from_json(dds::qos_to_json(qos))->transport == Transport::Node);
  }
  // What the rings and relays cannot honour goes on direct DDS, or is refused when named.
  for (const auto &qos : {qos_of({{"ownership", "exclusive"}}), qos_of({{"history", "keepall"}}),
                          qos_of({{"durability", "transient"}})}) {
    CHECK(profile::transport_for(qos) == Transport::Direct);
    CHECK_FALSE(profile::not_honoured(qos, Transport::Direct).has_value());
    CHECK(dds::qos_to_json(qos).at("transport") == "direct");
    CHECK(profile::not_honoured(qos, Transport::Node).has_value());
  }
  auto exclusive = qos_of({{"ownership", "exclusive"}, {"transport", "node"}});
  CHECK(profile::qos_inconsistency(exclusive) ==
        "transport=\"node\" does not honour ownership=\"exclusive\" (it delivers every "
        "writer): leave transport out (the domain then takes direct DDS) or give "
        "transport=\"direct\"");
  auto late = qos_of({{"durability", "transientlocal"}, {"transport", "tcp"}});
  CHECK_THAT(profile::qos_inconsistency(late).value_or(""),
             Catch::Contains("transport=\"tcp\" does not honour durability=\"transientlocal\""));
}
