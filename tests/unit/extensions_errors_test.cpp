// The semantic errors the readers raise about the RSCA profile extensions in profiles that
// validate against the schema (qos, timing, resourcedemand, filters, event channels, latency
// paths): one diagnostic each, with its rule and place. The extensions read when they are right
// are in extensions_test.cpp.
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

TEST_CASE("qos depth with keepall is an error", "[extensions][errors][qos]") {
  const std::string text =
      sad_text("", port_connection("c", R"(<qos history="keepall" depth="4"/>)"));
  const Diagnostic d = sad_error(text);
  CHECK(d.rule == "qos");
  CHECK(d.where.file == "extensions.sad.xml");
  CHECK(d.where.line == line_of(text, "<qos history=\"keepall\""));
  CHECK_THAT(d.message, Contains("depth") && Contains("keepall"));
}

TEST_CASE("qos strength without exclusive ownership is an error", "[extensions][errors][qos]") {
  for (std::string_view qos :
       {R"(<qos ownership="shared" strength="3"/>)", R"(<qos strength="3"/>)"}) {
    INFO(qos);
    const std::string text = sad_text("", port_connection("c", qos));
    const Diagnostic d = sad_error(text);
    CHECK(d.rule == "qos");
    CHECK(d.where.line == line_of(text, "<qos "));
    CHECK_THAT(d.message, Contains("strength") && Contains("exclusive"));
  }
}

TEST_CASE("a transport named that cannot honour the connection's QoS is an error, with the reason",
          "[extensions][errors][qos]") {
  struct Case {
    std::string_view qos;
    std::string_view says;
  };
  for (const Case &c :
       {Case{
            R"(<qos ownership="exclusive" strength="2" transport="node"/>)",
            R"(transport="node" does not honour ownership="exclusive" (it delivers every writer))"},
        Case{R"(<qos history="keepall" transport="node"/>)",
             R"(does not honour reliability="reliable" with history="keepall")"},
        Case{R"(<qos durability="transientlocal" transport="tcp"/>)",
             R"(transport="tcp" does not honour durability="transientlocal")"},
        Case{R"(<qos durability="persistent" transport="node"/>)",
             R"(transport="node" does not honour durability="persistent")"}}) {
    INFO(c.qos);
    const std::string text = sad_text("", port_connection("c", c.qos));
    const Diagnostic d = sad_error(text);
    CHECK(d.rule == "qos");
    CHECK(d.where.file == "extensions.sad.xml");
    CHECK(d.where.line == line_of(text, "<qos "));
    CHECK(d.where.column > 0);
    CHECK_THAT(d.message, Contains(std::string(c.says)) && Contains("transport=\"direct\""));
  }
  // The same QoS without a transport is read: the domain takes one that honours it.
  const std::string text = sad_text(
      "", port_connection("c", R"(<qos ownership="exclusive" strength="2" history="keepall"/>)"));
  CHECK(sad_of(text).connections.size() == 1);
}

TEST_CASE("a TCP stream with a liveliness lease, or to an event channel, is an error",
          "[extensions][errors][qos]") {
  // A stream tells a closed connection, not a writer that stopped asserting itself.
  const std::string leased = sad_text(
      "", port_connection("c", R"(<qos transport="tcp" liveliness="automatic" lease="300ms"/>)"));
  const Diagnostic d = sad_error(leased);
  CHECK(d.rule == "qos");
  CHECK(d.where.line == line_of(leased, "<qos transport=\"tcp\""));
  CHECK_THAT(d.message, Contains("tcp") && Contains("lease"));
  // A stream joins one uses port and one provides port: a channel has many members.
  const std::string channel = sad_text("", R"(    <connectinterface id="pub">
      <usesport>
        <usesidentifier>range_out</usesidentifier>
        <componentinstantiationref refid="Lidar_1"/>
      </usesport>
      <findby>
        <domainfinder type="eventchannel" name="RangeEvents"/>
      </findby>
      <qos transport="tcp"/>
    </connectinterface>)");
  const Diagnostic c = sad_error(channel);
  CHECK(c.rule == "qos");
  CHECK(c.where.line == line_of(channel, "<qos transport=\"tcp\""));
  CHECK_THAT(c.message, Contains("tcp") && Contains("event channel"));
  // Without either, a TCP stream reads.
  CHECK(sad_of(sad_text("", port_connection("c", R"(<qos transport="tcp"/>)")))
            .connections.at(0)
            .qos->transport == Transport::Tcp);
}

TEST_CASE("executiontime longer than the deadline is an error", "[extensions][errors][timing]") {
  const std::string text =
      sad_text(R"(<timing period="20ms" deadline="5ms" executiontime="6ms"/>)", "");
  const Diagnostic d = sad_error(text);
  CHECK(d.rule == "timing");
  CHECK(d.where.line == line_of(text, "<timing "));
  CHECK_THAT(d.message, Contains("deadline"));
}

TEST_CASE("executiontime longer than the period is an error", "[extensions][errors][timing]") {
  const std::string text = sad_text(R"(<timing period="5ms" executiontime="6ms"/>)", "");
  const Diagnostic d = sad_error(text);
  CHECK(d.rule == "timing");
  CHECK(d.where.line == line_of(text, "<timing "));
  CHECK_THAT(d.message, Contains("period") && Contains("100%"));
}

TEST_CASE("executiontime equal to deadline and period is accepted", "[extensions][timing]") {
  const auto sad =
      sad_of(sad_text(R"(<timing period="5ms" deadline="5ms" executiontime="5ms"/>)", ""));
  CHECK(sad.find_instantiation("Lidar_1")->timing->execution_time == ms(5));
}

TEST_CASE("utilization together with executiontime is an error",
          "[extensions][errors][resourcedemand]") {
  const std::string text = spd_text({implementation(
      "cpp", R"(<resourcedemand utilization="0.5" executiontime="1ms" period="10ms"/>)")});
  const Diagnostic d = spd_error(text);
  CHECK(d.rule == "resourcedemand");
  CHECK(d.where.file == "lidar.spd.xml");
  CHECK(d.where.line == line_of(text, "<resourcedemand "));
  CHECK_THAT(d.message, Contains("utilization") && Contains("not both"));
}

TEST_CASE("executiontime and period go together", "[extensions][errors][resourcedemand]") {
  for (std::string_view demand : {R"(<resourcedemand executiontime="1ms" memory="1MiB"/>)",
                                  R"(<resourcedemand period="10ms"/>)"}) {
    INFO(demand);
    const std::string text = spd_text({implementation("cpp", demand)});
    const Diagnostic d = spd_error(text);
    CHECK(d.rule == "resourcedemand");
    CHECK(d.where.line == line_of(text, "<resourcedemand "));
    CHECK_THAT(d.message, Contains("give both or neither"));
  }
}

TEST_CASE("a filter on a connection that does not subscribe is an error",
          "[extensions][errors][filter]") {
  const std::string text = sad_text("", port_connection("direct", "<filter>range &gt; 1</filter>"));
  const Diagnostic d = sad_error(text);
  CHECK(d.rule == "filter");
  CHECK(d.where.line == line_of(text, "<filter>"));
  CHECK_THAT(d.message, Contains("connection \"direct\"") && Contains("does not subscribe"));
}

TEST_CASE("a filter on a publisher is an error", "[extensions][errors][filter]") {
  const std::string text = sad_text("", R"(    <connectinterface id="pub">
      <usesport>
        <usesidentifier>range_out</usesidentifier>
        <componentinstantiationref refid="Lidar_1"/>
      </usesport>
      <findby>
        <domainfinder type="eventchannel" name="RangeEvents"/>
      </findby>
      <filter>range &gt; 1</filter>
    </connectinterface>)");
  const Diagnostic d = sad_error(text);
  CHECK(d.rule == "filter");
  CHECK(d.where.line == line_of(text, "<filter>"));
  CHECK_THAT(d.message, Contains("connection \"pub\""));
}

TEST_CASE("a connection between two event channels is an error", "[extensions][errors]") {
  const std::string text = sad_text("", R"(    <connectinterface id="bridge">
      <usesport>
        <usesidentifier>x</usesidentifier>
        <findby>
          <domainfinder type="eventchannel" name="A"/>
        </findby>
      </usesport>
      <findby>
        <domainfinder type="eventchannel" name="B"/>
      </findby>
    </connectinterface>)");
  const Diagnostic d = sad_error(text);
  CHECK(d.rule == "connection");
  CHECK(d.where.line == line_of(text, "<connectinterface id=\"bridge\""));
  CHECK_THAT(d.message, Contains("two event channels"));
}

TEST_CASE("a latency path naming an unknown instance is an error", "[extensions][errors]") {
  const std::string text = sad_text("", "", R"(  <latencyconstraints>
    <latencypath id="p" bound="5ms">
      <componentinstantiationref refid="Lidar_1"/>
      <componentinstantiationref refid="Ghost_1"/>
    </latencypath>
  </latencyconstraints>)");
  const Diagnostic d = sad_error(text);
  CHECK(d.rule == "dangling-ref");
  CHECK(d.where.line == line_of(text, "refid=\"Ghost_1\""));
  CHECK_THAT(d.message, Contains("latency path \"p\"") && Contains("Ghost_1"));
}
