// The RSCA profile extensions (timing, qos, filter, latencyconstraints, resourcedemand) read from
// inline profiles (extensions_fixture.hpp); the semantic errors the readers raise about them are
// in extensions_errors_test.cpp.
#include "profile/descriptor.hpp"

#include <catch2/catch.hpp>

#include <chrono>
#include <string>
#include <string_view>
#include <vector>

#include "extensions_fixture.hpp"

using namespace rsca;
using namespace rsca::profile;
using namespace rsca::test;
using namespace std::chrono_literals;
using Catch::Matchers::Contains;

TEST_CASE("qos attributes map to their enums, integers and durations", "[extensions][qos]") {
  const std::string text = sad_text(
      "", port_connection("c1", R"(<qos reliability="reliable" durability="volatile" )"
                                R"(history="keeplast" depth="16" deadline="100ms" )"
                                R"(latencybudget="5ms" transportpriority="-3" )"
                                R"(liveliness="automatic" lease="2s" ownership="exclusive" )"
                                R"(strength="7"/>)") +
              port_connection("c2", R"(<qos reliability="besteffort" durability="transientlocal" )"
                                    R"(history="keepall" liveliness="manualbyparticipant" )"
                                    R"(lease="infinite" ownership="shared"/>)") +
              port_connection("c3", R"(<qos durability="transient" liveliness="manualbytopic"/>)") +
              port_connection("c4", R"(<qos durability="persistent"/>)"));
  const SoftwareAssembly sad = sad_of(text);
  REQUIRE(sad.connections.size() == 4);

  const auto &q1 = connection(sad, "c1").qos;
  REQUIRE(q1.has_value());
  CHECK(q1->reliability == Reliability::Reliable);
  CHECK(q1->durability == Durability::Volatile);
  CHECK(q1->history == History::KeepLast);
  CHECK(q1->depth == 16u);
  CHECK(q1->deadline == ms(100));
  CHECK(q1->latency_budget == ms(5));
  CHECK(q1->transport_priority == -3);
  CHECK(q1->liveliness == Liveliness::Automatic);
  CHECK(q1->lease == Duration{2s});
  CHECK(q1->ownership == Ownership::Exclusive);
  CHECK(q1->strength == 7);
  CHECK(q1->where.line == line_of(text, "<qos reliability=\"reliable\""));
  CHECK(q1->where.file == "extensions.sad.xml");

  const auto &q2 = connection(sad, "c2").qos;
  REQUIRE(q2.has_value());
  CHECK(q2->reliability == Reliability::BestEffort);
  CHECK(q2->durability == Durability::TransientLocal);
  CHECK(q2->history == History::KeepAll);
  CHECK_FALSE(q2->depth.has_value());
  CHECK(q2->liveliness == Liveliness::ManualByParticipant);
  REQUIRE(q2->lease.has_value());
  CHECK(q2->lease->infinite());
  CHECK(q2->ownership == Ownership::Shared);
  CHECK_FALSE(q2->strength.has_value());

  const auto &q3 = connection(sad, "c3").qos;
  REQUIRE(q3.has_value());
  CHECK(q3->durability == Durability::Transient);
  CHECK(q3->liveliness == Liveliness::ManualByTopic);
  // Absent attributes stay absent: no requirement.
  CHECK_FALSE(q3->reliability.has_value());
  CHECK_FALSE(q3->history.has_value());
  CHECK_FALSE(q3->deadline.has_value());
  CHECK_FALSE(q3->latency_budget.has_value());
  CHECK_FALSE(q3->transport_priority.has_value());
  CHECK_FALSE(q3->ownership.has_value());

  CHECK(connection(sad, "c4").qos->durability == Durability::Persistent);
}

TEST_CASE("qos enum values print as written", "[extensions][qos]") {
  CHECK(to_string(Reliability::BestEffort) == "besteffort");
  CHECK(to_string(Durability::TransientLocal) == "transientlocal");
  CHECK(to_string(History::KeepAll) == "keepall");
  CHECK(to_string(Liveliness::ManualByTopic) == "manualbytopic");
  CHECK(to_string(Ownership::Exclusive) == "exclusive");
  CHECK(to_string(Criticality::Safety) == "safety");
}

TEST_CASE("qos values outside the schema's ranges are refused", "[extensions][qos][schema]") {
  for (std::string_view qos :
       {R"(<qos depth="0"/>)", R"(<qos reliability="Reliable"/>)", R"(<qos deadline="10 ms"/>)",
        R"(<qos transportpriority="3000000000"/>)", R"(<qos history="keepfirst"/>)"}) {
    INFO(qos);
    const auto doc = read_xml_profile_text(sad_text("", port_connection("c", qos)), "q.sad.xml");
    REQUIRE_FALSE(doc.has_value());
    CHECK(doc.error().diagnostics().front().rule == "schema");
  }
}

TEST_CASE("timing of a component instance", "[extensions][timing]") {
  const std::string text = sad_text(R"(<timing period="20ms" deadline="15ms" executiontime="2ms" )"
                                    R"(priority="10" criticality="safety"/>)",
                                    "");
  const SoftwareAssembly sad = sad_of(text);
  const ComponentInstantiation *lidar = sad.find_instantiation("Lidar_1");
  REQUIRE(lidar != nullptr);
  REQUIRE(lidar->timing.has_value());
  CHECK(lidar->timing->period == ms(20));
  CHECK(lidar->timing->deadline == ms(15));
  CHECK(lidar->timing->execution_time == ms(2));
  CHECK(lidar->timing->priority == 10u);
  CHECK(lidar->timing->criticality == Criticality::Safety);
  CHECK(lidar->timing->where.line == line_of(text, "<timing "));
  // The other instances say nothing about timing.
  CHECK_FALSE(sad.find_instantiation("Planner_1")->timing.has_value());
  CHECK_FALSE(sad.find_instantiation("Motor_1")->timing.has_value());
}

TEST_CASE("every criticality level, and partial timing", "[extensions][timing]") {
  const std::pair<std::string_view, Criticality> levels[] = {{"low", Criticality::Low},
                                                             {"medium", Criticality::Medium},
                                                             {"high", Criticality::High},
                                                             {"safety", Criticality::Safety}};
  for (const auto &[name, level] : levels) {
    INFO(name);
    const auto sad = sad_of(sad_text("<timing criticality=\"" + std::string(name) + "\"/>", ""));
    const auto &timing = sad.find_instantiation("Lidar_1")->timing;
    REQUIRE(timing.has_value());
    CHECK(timing->criticality == level);
    CHECK_FALSE(timing->period.has_value());
    CHECK_FALSE(timing->deadline.has_value());
    CHECK_FALSE(timing->execution_time.has_value());
    CHECK_FALSE(timing->priority.has_value());
  }
  const auto sad = sad_of(sad_text(R"(<timing period="1.5s" deadline="infinite"/>)", ""));
  const auto &timing = sad.find_instantiation("Lidar_1")->timing;
  CHECK(timing->period == Duration{1500ms});
  REQUIRE(timing->deadline.has_value());
  CHECK(timing->deadline->infinite());
  CHECK_FALSE(timing->criticality.has_value());
}

TEST_CASE("resourcedemand with utilization, memory and bandwidth", "[extensions][resourcedemand]") {
  const std::string text =
      spd_text({implementation("share", R"(<resourcedemand utilization="0.25" memory="64MiB" )"
                                        R"(bandwidth="10Mbps"/>)"),
                implementation("budget", R"(<resourcedemand executiontime="2ms" period="10ms" )"
                                         R"(memory="1.5GB" bandwidth="9600bps"/>)"),
                implementation("kilo", R"(<resourcedemand bandwidth="1.5kbps" memory="512B"/>)"),
                implementation("giga", R"(<resourcedemand bandwidth="1Gbps" utilization="1"/>)"),
                implementation("none", "")});
  const SoftPkg spd = spd_of(text);
  REQUIRE(spd.implementations.size() == 5);

  const auto &share = spd.find_implementation("share")->resource_demand;
  REQUIRE(share.has_value());
  CHECK(share->utilization.value() == Approx(0.25));
  CHECK(share->memory_bytes == 67'108'864u);
  CHECK(share->bandwidth_bps.value() == Approx(10e6));
  CHECK_FALSE(share->execution_time.has_value());
  CHECK_FALSE(share->period.has_value());
  CHECK(share->where.line == line_of(text, "<resourcedemand utilization=\"0.25\""));

  const auto &budget = spd.find_implementation("budget")->resource_demand;
  REQUIRE(budget.has_value());
  CHECK_FALSE(budget->utilization.has_value());
  CHECK(budget->execution_time == ms(2));
  CHECK(budget->period == ms(10));
  CHECK(budget->memory_bytes == 1'500'000'000u);
  CHECK(budget->bandwidth_bps.value() == Approx(9600.0));

  const auto &kilo = spd.find_implementation("kilo")->resource_demand;
  CHECK(kilo->bandwidth_bps.value() == Approx(1500.0));
  CHECK(kilo->memory_bytes == 512u);
  CHECK_FALSE(kilo->utilization.has_value());

  const auto &giga = spd.find_implementation("giga")->resource_demand;
  CHECK(giga->bandwidth_bps.value() == Approx(1e9));
  CHECK(giga->utilization.value() == Approx(1.0));
  CHECK_FALSE(giga->memory_bytes.has_value());

  CHECK_FALSE(spd.find_implementation("none")->resource_demand.has_value());
}

TEST_CASE("utilization must be above 0 and at most 1", "[extensions][resourcedemand][schema]") {
  for (std::string_view u : {"0", "1.5", "-0.1", "half"}) {
    INFO("utilization " << u);
    const auto doc =
        read_xml_profile_text(spd_text({implementation("cpp", "<resourcedemand utilization=\"" +
                                                                  std::string(u) + "\"/>")}),
                              "u.spd.xml");
    REQUIRE_FALSE(doc.has_value());
    CHECK(doc.error().diagnostics().front().rule == "schema");
  }
}

TEST_CASE("latency paths list instances in data-flow order", "[extensions][latency]") {
  const std::string text = sad_text("", "", R"(  <latencyconstraints>
    <latencypath id="sense_to_act" bound="50ms">
      <componentinstantiationref refid="Lidar_1"/>
      <componentinstantiationref refid="Planner_1"/>
      <componentinstantiationref refid="Motor_1"/>
    </latencypath>
    <latencypath id="plan_to_act" bound="1.5s">
      <componentinstantiationref refid="Planner_1"/>
      <componentinstantiationref refid="Motor_1"/>
    </latencypath>
  </latencyconstraints>)");
  const SoftwareAssembly sad = sad_of(text);
  REQUIRE(sad.latency_paths.size() == 2);
  const LatencyPath &first = sad.latency_paths[0];
  CHECK(first.id == "sense_to_act");
  CHECK(first.bound == ms(50));
  CHECK(first.components == std::vector<std::string>{"Lidar_1", "Planner_1", "Motor_1"});
  CHECK(first.where.line == line_of(text, "<latencypath id=\"sense_to_act\""));
  const LatencyPath &second = sad.latency_paths[1];
  CHECK(second.id == "plan_to_act");
  CHECK(second.bound == Duration{1500ms});
  CHECK(second.components == std::vector<std::string>{"Planner_1", "Motor_1"});
}

TEST_CASE("a latency path of one instance is refused by the schema", "[extensions][latency]") {
  const auto doc = read_xml_profile_text(sad_text("", "", R"(  <latencyconstraints>
    <latencypath id="p" bound="5ms">
      <componentinstantiationref refid="Lidar_1"/>
    </latencypath>
  </latencyconstraints>)"),
                                         "l.sad.xml");
  REQUIRE_FALSE(doc.has_value());
  CHECK(doc.error().diagnostics().front().rule == "schema");
}

TEST_CASE("event-channel publisher and filtered subscriber", "[extensions][eventchannel]") {
  const std::string text = sad_text("", R"(    <connectinterface id="range_pub">
      <usesport>
        <usesidentifier>range_out</usesidentifier>
        <componentinstantiationref refid="Lidar_1"/>
      </usesport>
      <findby>
        <domainfinder type="eventchannel" name="RangeEvents"/>
      </findby>
    </connectinterface>
    <connectinterface id="range_sub">
      <usesport>
        <usesidentifier>range_out</usesidentifier>
        <findby>
          <domainfinder type="eventchannel" name="RangeEvents"/>
        </findby>
      </usesport>
      <providesport>
        <providesidentifier>range_in</providesidentifier>
        <componentinstantiationref refid="Planner_1"/>
      </providesport>
      <qos reliability="besteffort" history="keeplast" depth="1"/>
      <filter>range &lt; 10.0 &amp;&amp; valid</filter>
    </connectinterface>
    <connectinterface id="log_pub">
      <usesport>
        <usesidentifier>log_out</usesidentifier>
        <componentinstantiationref refid="Motor_1"/>
      </usesport>
      <findby>
        <domainfinder type="log" name="MotorLog"/>
      </findby>
    </connectinterface>)");
  const SoftwareAssembly sad = sad_of(text);
  REQUIRE(sad.connections.size() == 3);

  const Connection &pub = connection(sad, "range_pub");
  CHECK(pub.publishes_to_channel());
  CHECK_FALSE(pub.subscribes_to_channel());
  CHECK(pub.uses.port == "range_out");
  CHECK(pub.uses.target.kind == EndpointTarget::Kind::ComponentInstantiation);
  CHECK(pub.uses.target.refid == "Lidar_1");
  CHECK(pub.provides.kind == ProvidesEnd::Kind::FindBy);
  CHECK(pub.provides.target.findby.kind == FindBy::Kind::DomainFinder);
  CHECK(pub.provides.target.findby.type == "eventchannel");
  CHECK(pub.provides.target.findby.name == "RangeEvents");
  CHECK_FALSE(pub.filter.has_value());
  CHECK_FALSE(pub.qos.has_value());

  const Connection &sub = connection(sad, "range_sub");
  CHECK(sub.subscribes_to_channel());
  CHECK_FALSE(sub.publishes_to_channel());
  CHECK(sub.uses.target.kind == EndpointTarget::Kind::FindBy);
  CHECK(sub.uses.target.findby.name == "RangeEvents");
  CHECK(sub.provides.kind == ProvidesEnd::Kind::Port);
  CHECK(sub.provides.port == "range_in");
  CHECK(sub.provides.target.refid == "Planner_1");
  REQUIRE(sub.filter.has_value());
  CHECK(*sub.filter == "range < 10.0 && valid");
  REQUIRE(sub.qos.has_value());
  CHECK(sub.qos->depth == 1u);

  // A domainfinder of another type is not an event channel.
  const Connection &log = connection(sad, "log_pub");
  CHECK(log.provides.kind == ProvidesEnd::Kind::FindBy);
  CHECK(log.provides.target.findby.type == "log");
  CHECK_FALSE(log.publishes_to_channel());
  CHECK_FALSE(log.subscribes_to_channel());
}

TEST_CASE("a plain SCA profile has every extension empty", "[extensions][plain]") {
  const SoftwareAssembly sad = sad_of(sad_text("", port_connection("plain", "")));
  CHECK(sad.latency_paths.empty());
  for (const auto &placement : sad.placements)
    for (const auto &ci : placement.instantiations)
      CHECK_FALSE(ci.timing.has_value());
  REQUIRE(sad.connections.size() == 1);
  const Connection &c = sad.connections.front();
  CHECK(c.id == "plain");
  CHECK_FALSE(c.qos.has_value());
  CHECK_FALSE(c.filter.has_value());
  CHECK_FALSE(c.publishes_to_channel());
  CHECK_FALSE(c.subscribes_to_channel());
  CHECK(c.uses.target.refid == "Lidar_1");
  CHECK(c.provides.target.refid == "Planner_1");

  const SoftPkg spd = spd_of(spd_text({implementation("cpp", "")}));
  REQUIRE(spd.implementations.size() == 1);
  CHECK_FALSE(spd.implementations.front().resource_demand.has_value());
  CHECK(spd.implementations.front().os.front().name == "Linux");
}
