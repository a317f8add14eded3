// Inline profiles for the tests of the RSCA profile extensions: a SAD of three components with
// slots for a component's timing, the connections and trailing sections, an SPD of Lidar
// implementations, readers that fail the test when the profile does not validate, and the one
// diagnostic a reader gives. Used by extensions_test.cpp and extensions_errors_test.cpp.
#pragma once

#include <chrono>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <catch2/catch.hpp>

#include "profile/descriptor.hpp"

namespace rsca::test {

using namespace rsca::profile;

// Three components, with a slot for Lidar_1's timing, the connections and the trailing sections.
constexpr std::string_view kSadTemplate = R"(<?xml version="1.0" encoding="UTF-8"?>
<softwareassembly id="DCE:7f2c1a52-0001-4a6e-9d43-2a1f0c0e0001" name="Extensions">
  <componentfiles>
    <componentfile id="Lidar_spd" type="SPD">
      <localfile name="/components/Lidar/Lidar.spd.xml"/>
    </componentfile>
    <componentfile id="Planner_spd" type="SPD">
      <localfile name="/components/Planner/Planner.spd.xml"/>
    </componentfile>
    <componentfile id="Motor_spd" type="SPD">
      <localfile name="/components/Motor/Motor.spd.xml"/>
    </componentfile>
  </componentfiles>
  <partitioning>
    <componentplacement>
      <componentfileref refid="Lidar_spd"/>
      <componentinstantiation id="Lidar_1" startorder="0">
        <usagename>Lidar_1</usagename>
        <findcomponent>
          <namingservice name="Lidar_1"/>
        </findcomponent>
        @TIMING@
      </componentinstantiation>
    </componentplacement>
    <componentplacement>
      <componentfileref refid="Planner_spd"/>
      <componentinstantiation id="Planner_1" startorder="1">
        <usagename>Planner_1</usagename>
      </componentinstantiation>
    </componentplacement>
    <componentplacement>
      <componentfileref refid="Motor_spd"/>
      <componentinstantiation id="Motor_1" startorder="2">
        <usagename>Motor_1</usagename>
      </componentinstantiation>
    </componentplacement>
  </partitioning>
  <assemblycontroller>
    <componentinstantiationref refid="Planner_1"/>
  </assemblycontroller>
  <connections>
@CONNECTIONS@
  </connections>
@TAIL@
</softwareassembly>
)";

// One implementation per slot entry; each gets the `extra` text as its last child.
constexpr std::string_view kSpdHead = R"(<?xml version="1.0" encoding="UTF-8"?>
<softpkg id="DCE:7f2c1a52-0002-4a6e-9d43-2a1f0c0e0002" name="Lidar" version="1.0">
  <author>
    <name>rsca</name>
  </author>
)";

inline std::string replaced(std::string text, std::string_view slot, std::string_view content) {
  const auto at = text.find(slot);
  REQUIRE(at != std::string::npos);
  text.replace(at, slot.size(), content);
  return text;
}

inline std::string sad_text(std::string_view timing, std::string_view connections,
                            std::string_view tail = "") {
  std::string text(kSadTemplate);
  text = replaced(std::move(text), "@TIMING@", timing);
  text = replaced(std::move(text), "@CONNECTIONS@", connections);
  return replaced(std::move(text), "@TAIL@", tail);
}

// A port-to-port connection Lidar_1.range_out -> Planner_1.range_in ending with `extra`.
inline std::string port_connection(std::string_view id, std::string_view extra) {
  return "    <connectinterface id=\"" + std::string(id) + R"(">
      <usesport>
        <usesidentifier>range_out</usesidentifier>
        <componentinstantiationref refid="Lidar_1"/>
      </usesport>
      <providesport>
        <providesidentifier>range_in</providesidentifier>
        <componentinstantiationref refid="Planner_1"/>
      </providesport>
      )" +
         std::string(extra) + "\n    </connectinterface>\n";
}

inline std::string implementation(std::string_view id, std::string_view extra) {
  return "  <implementation id=\"" + std::string(id) + R"(">
    <code type="Executable">
      <localfile name="bin/lidar"/>
      <entrypoint>bin/lidar</entrypoint>
    </code>
    <os name="Linux"/>
    <processor name="x86_64"/>
    )" + std::string(extra) +
         "\n  </implementation>\n";
}

inline std::string spd_text(const std::vector<std::string> &implementations) {
  std::string text(kSpdHead);
  for (const auto &i : implementations)
    text += i;
  return text + "</softpkg>\n";
}

// The 1-based number of the first line of `text` containing `needle`.
inline int line_of(std::string_view text, std::string_view needle) {
  const auto at = text.find(needle);
  REQUIRE(at != std::string_view::npos);
  int line = 1;
  for (std::size_t i = 0; i < at; ++i)
    line += text[i] == '\n' ? 1 : 0;
  return line;
}

inline XmlDocument document(const std::string &text, const std::string &file) {
  auto doc = read_xml_profile_text(text, file);
  if (!doc)
    FAIL("the profile does not validate:\n" << doc.error().to_string() << "\n" << text);
  return std::move(*doc);
}

inline SoftwareAssembly sad_of(const std::string &text) {
  auto sad = read_sad(document(text, "extensions.sad.xml"));
  if (!sad)
    FAIL("read_sad failed:\n" << sad.error().to_string());
  return std::move(*sad);
}

inline SoftPkg spd_of(const std::string &text) {
  auto spd = read_spd(document(text, "lidar.spd.xml"));
  if (!spd)
    FAIL("read_spd failed:\n" << spd.error().to_string());
  return std::move(*spd);
}

// The one diagnostic a reader gives for a profile that validates against the schema.
template <typename T>
Diagnostic only_error(const Expected<T> &result) {
  REQUIRE_FALSE(result.has_value());
  const auto &diagnostics = result.error().diagnostics();
  INFO(result.error().to_string());
  REQUIRE(diagnostics.size() == 1);
  CHECK(diagnostics.front().severity == Severity::Error);
  return diagnostics.front();
}

inline Diagnostic sad_error(const std::string &text) {
  return only_error(read_sad(document(text, "extensions.sad.xml")));
}

inline Diagnostic spd_error(const std::string &text) {
  return only_error(read_spd(document(text, "lidar.spd.xml")));
}

inline const Connection &connection(const SoftwareAssembly &sad, std::string_view id) {
  for (const auto &c : sad.connections)
    if (c.id == id)
      return c;
  FAIL("no connection " << id);
  throw;
}

inline Duration ms(long long n) {
  return Duration{std::chrono::milliseconds(n)};
}

} // namespace rsca::test
