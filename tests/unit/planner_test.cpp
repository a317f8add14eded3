// Unit tests of the placement planner (allocator/planner.hpp): one test case per constraint
// kind, each on hand-made devices and software packages (planner_fixture.hpp), with every
// expected value worked out by hand in a comment next to it. This file: what one device accepts
// (os and processor, matching properties, softpkg dependencies, capacities);
// planner_placement_test.cpp, planner_timing_test.cpp and planner_strategy_test.cpp the rest.
#include "allocator/planner.hpp"
#include "planner_fixture.hpp"

#include <catch2/catch.hpp>

#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

using namespace rsca;
using namespace rsca::allocator;
using namespace rsca::test;
using std::chrono::milliseconds;

// 1
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: os and processor select the implementation", "[planner]") {
  const auto state = domain_state({gpp_device("n1:GPP", "n1", 100, 1024, "Linux", "x86_64")});

  SECTION("the second implementation is tried when the first does not fit") {
    // arm needs armv7, the device is x86_64: only x86 fits.
    auto pkg =
        softpkg("comp", {ImplSpec("arm").processor("armv7"), ImplSpec("x86").processor("x86_64")});
    const Plan plan = require_plan(make_plan(state, request_of({component_request("c", pkg)})));
    CHECK(device_of(plan, "c") == "n1:GPP");
    CHECK(implementation_of(plan, "c") == "x86");
  }

  SECTION("os: any of the listed os names matches") {
    // qnx needs QNX (device is Linux); multi lists QNX or Linux, so it fits.
    auto pkg =
        softpkg("comp", {ImplSpec("qnx").os("QNX"), ImplSpec("multi").os("QNX").os("Linux")});
    const Plan plan = require_plan(make_plan(state, request_of({component_request("c", pkg)})));
    CHECK(implementation_of(plan, "c") == "multi");
  }

  SECTION("no implementation fits: rejected with the mismatch per device and implementation") {
    auto pkg = softpkg("comp", {ImplSpec("arm").processor("armv7"), ImplSpec("qnx").os("QNX")});
    const auto rejections =
        require_rejection(make_plan(state, request_of({component_request("c", pkg)})));
    REQUIRE(rejections.size() == 1);
    CHECK(rejections[0].instance == "c");
    CHECK(rejections[0].reasons ==
          std::vector<std::string>{
              "n1:GPP (arm): processor_name is x86_64, implementation arm needs armv7",
              "n1:GPP (qnx): os_name is Linux, implementation qnx needs QNX"});
  }
}

// 2
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: matching allocation properties compare device value action required",
          "[planner]") {
  struct Row {
    profile::Action action;
    const char *device_value;
    const char *required;
    bool satisfied; // device_value <action> required, the device's value on the left
  };
  using A = profile::Action;
  const Row rows[] = {
      {A::Eq, "8", "8", true},       // 8 == 8
      {A::Eq, "8", "4", false},      // 8 == 4 false
      {A::Ne, "8", "4", true},       // 8 != 4
      {A::Ne, "8", "8", false},      // 8 != 8 false
      {A::Gt, "8", "4", true},       // 8 > 4
      {A::Gt, "4", "8", false},      // 4 > 8 false (the required value is on the right)
      {A::Gt, "8", "8", false},      // 8 > 8 false
      {A::Gt, "10", "9", true},      // numbers compare as numbers: 10 > 9 (as text "10" < "9")
      {A::Lt, "4", "8", true},       // 4 < 8
      {A::Lt, "8", "4", false},      // 8 < 4 false
      {A::Ge, "8", "8", true},       // 8 >= 8
      {A::Ge, "4", "8", false},      // 4 >= 8 false
      {A::Le, "8", "8", true},       // 8 <= 8
      {A::Le, "8", "4", false},      // 8 <= 4 false
      {A::Eq, "ros2", "ros2", true}, // text equality
      {A::Ne, "ros2", "dds", true},  // text inequality
  };
  SECTION("every action, the device's value on the left") {
    for (const auto &row : rows) {
      INFO("device " << row.device_value << " " << profile::to_string(row.action) << " required "
                     << row.required);
      Device d = gpp_device("n1:GPP", "n1");
      d.properties.push_back({"DCE:bogomips", "bogomips", row.device_value, row.action});
      // The requirement names the property by id; name lookup is covered by the next check.
      auto pkg = softpkg("comp", {ImplSpec("cpp").needs("DCE:bogomips", row.required)});
      const auto result = make_plan(domain_state({d}), request_of({component_request("c", pkg)}));
      CHECK(result.has_value() == row.satisfied);
    }
  }

  SECTION("the reason names the property, its value, the action and the requirement") {
    Device d = gpp_device("n1:GPP", "n1");
    d.properties.push_back({"DCE:bogomips", "bogomips", "4", profile::Action::Gt});
    auto pkg = softpkg("comp", {ImplSpec("cpp").needs("bogomips", "8")}); // by name: 4 > 8 false
    const auto rejections =
        require_rejection(make_plan(domain_state({d}), request_of({component_request("c", pkg)})));
    REQUIRE(rejections.size() == 1);
    CHECK(
        rejections[0].reasons ==
        std::vector<std::string>{
            "n1:GPP (cpp): implementation cpp depends on a device that bogomips is 4, needs gt 8"});
  }

  SECTION("a device without the property does not match") {
    auto pkg = softpkg("comp", {ImplSpec("cpp").needs("gpu_model", "orin")});
    const auto rejections = require_rejection(make_plan(domain_state({gpp_device("n1:GPP", "n1")}),
                                                        request_of({component_request("c", pkg)})));
    CHECK_THAT(to_string(rejections), Catch::Contains("has no allocation property gpu_model"));
  }
}

// 3
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: softpkg dependencies must load on the component's device", "[planner]") {
  // n1 runs QNX, n2 Linux; the component itself runs anywhere.
  const auto state =
      domain_state({gpp_device("n1:GPP", "n1", 100, 1024, "QNX"), gpp_device("n2:GPP", "n2")});

  SECTION("a dependency whose only implementation needs Linux takes the component to n2") {
    auto lib = softpkg("libdsp", {ImplSpec("dsp_linux").os("Linux")});
    auto pkg = softpkg("comp", {ImplSpec("cpp").depends_on(lib)});
    // Pack would take n1:GPP first (equal load, first id); the dependency rules it out.
    const Plan plan = require_plan(make_plan(state, request_of({component_request("c", pkg)})));
    CHECK(device_of(plan, "c") == "n2:GPP");
  }

  SECTION("dependencies are matched recursively") {
    // comp -> libdsp (any os) -> libmath (QNX only): only n1 can load the whole chain.
    auto math = softpkg("libmath", {ImplSpec("math_qnx").os("QNX")});
    auto dsp = softpkg("libdsp", {ImplSpec("dsp").depends_on(math)});
    auto pkg = softpkg("comp", {ImplSpec("cpp").depends_on(dsp)});
    const Plan plan = require_plan(make_plan(state, request_of({component_request("c", pkg)})));
    CHECK(device_of(plan, "c") == "n1:GPP");

    // Without the QNX node nothing can host it, and the reason follows the chain.
    const auto rejections = require_rejection(make_plan(domain_state({gpp_device("n2:GPP", "n2")}),
                                                        request_of({component_request("c", pkg)})));
    CHECK(
        rejections[0].reasons ==
        std::vector<std::string>{"n2:GPP (cpp): dependency libdsp: dependency libmath: os_name is "
                                 "Linux, implementation math_qnx needs QNX"});
  }

  SECTION("an implref restricts the dependency to that implementation") {
    auto lib =
        softpkg("libdsp", {ImplSpec("dsp_qnx").os("QNX"), ImplSpec("dsp_linux").os("Linux")});
    const auto linux_only = domain_state({gpp_device("n2:GPP", "n2")});
    auto any = softpkg("comp", {ImplSpec("cpp").depends_on(lib)});
    CHECK(make_plan(linux_only, request_of({component_request("c", any)})).has_value());
    auto pinned = softpkg("comp", {ImplSpec("cpp").depends_on(lib, "dsp_qnx")});
    CHECK_FALSE(make_plan(linux_only, request_of({component_request("c", pinned)})).has_value());
  }

  SECTION("the component's second implementation is tried when the first's dependency fails") {
    auto qnx_lib = softpkg("libq", {ImplSpec("q").os("QNX")});
    auto pkg = softpkg("comp", {ImplSpec("with_q").depends_on(qnx_lib), ImplSpec("plain")});
    const Plan plan = require_plan(make_plan(domain_state({gpp_device("n2:GPP", "n2")}),
                                             request_of({component_request("c", pkg)})));
    CHECK(implementation_of(plan, "c") == "plain");
  }
}

// 4
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: capacities are subtracted per component", "[planner]") {
  const auto state = domain_state({gpp_device("n1:GPP", "n1", 100, 1024)});

  SECTION("demands add up on the device") {
    auto a = softpkg("a", {ImplSpec("cpp").utilization(0.6).memory_mib(512)});
    auto b = softpkg("b", {ImplSpec("cpp").utilization(0.3).memory_mib(256)});
    const Plan plan = require_plan(
        make_plan(state, request_of({component_request("a", a), component_request("b", b)})));
    // a demands 0.6 * 100 = 60 % CPU and 512 MiB; b 30 % and 256 MiB.
    CHECK(placement_of(plan, "a").demand.at(kCpuCapacity) == Approx(60));
    CHECK(placement_of(plan, "a").demand.at(kMemCapacity) == 512);
    DomainState committed = state;
    commit(committed, plan);
    CHECK(allocated(committed, "n1:GPP", kCpuCapacity) == Approx(90)); // 60 + 30
    CHECK(allocated(committed, "n1:GPP", kMemCapacity) == 768);        // 512 + 256
  }

  SECTION("an application whose sum does not fit is rejected, naming the device") {
    // a takes 60 %, leaving 40 %; b needs 50 %.
    auto a = softpkg("a", {ImplSpec("cpp").utilization(0.6)});
    auto b = softpkg("b", {ImplSpec("cpp").utilization(0.5)});
    const auto rejections = require_rejection(
        make_plan(state, request_of({component_request("a", a), component_request("b", b)})));
    REQUIRE(rejections.size() == 1);
    CHECK(rejections[0].instance == "b");
    CHECK(rejections[0].reasons ==
          std::vector<std::string>{"n1:GPP (cpp): cpu_capacity needs 50.0% CPU, 40.0% CPU free"});
  }

  SECTION("memory: 768 + 512 MiB exceed 1024 MiB") {
    auto a = softpkg("a", {ImplSpec("cpp").memory_mib(768)});
    auto b = softpkg("b", {ImplSpec("cpp").memory_mib(512)});
    const auto rejections = require_rejection(
        make_plan(state, request_of({component_request("a", a), component_request("b", b)})));
    CHECK_THAT(to_string(rejections),
               Catch::Contains("n1:GPP (cpp): mem_capacity needs 512 MiB, 256 MiB free"));
  }

  SECTION("exactly full fits") {
    // 10 + 20 + 70 = 100 % and 256 + 256 + 512 = 1024 MiB. In doubles 0.7 * 100 is
    // 70.00000000000001, so the float sum exceeds 100 by about 1e-14: the planner must not
    // reject that.
    auto c1 = softpkg("c1", {ImplSpec("cpp").utilization(0.1).memory_mib(256)});
    auto c2 = softpkg("c2", {ImplSpec("cpp").utilization(0.2).memory_mib(256)});
    auto c3 = softpkg("c3", {ImplSpec("cpp").utilization(0.7).memory_mib(512)});
    PlanRequest full = request_of(
        {component_request("c1", c1), component_request("c2", c2), component_request("c3", c3)});
    const Plan plan = require_plan(make_plan(state, full));
    DomainState committed = state;
    commit(committed, plan);
    CHECK(allocated(committed, "n1:GPP", kCpuCapacity) == Approx(100));
    CHECK(allocated(committed, "n1:GPP", kMemCapacity) == 1024);

    // One MiB more does not.
    auto c4 = softpkg("c4", {ImplSpec("cpp").memory_mib(1)});
    full.components.push_back(component_request("c4", c4));
    const auto rejections = require_rejection(make_plan(state, full));
    CHECK_THAT(to_string(rejections), Catch::Contains("mem_capacity needs 1 MiB, 0 MiB free"));
  }

  SECTION("what is already allocated counts") {
    DomainState loaded = state;
    loaded["n1:GPP"].load.allocated[kCpuCapacity] = 70; // 30 % free
    auto a = softpkg("a", {ImplSpec("cpp").utilization(0.4)});
    const auto rejections =
        require_rejection(make_plan(loaded, request_of({component_request("a", a)})));
    CHECK(rejections[0].reasons ==
          std::vector<std::string>{"n1:GPP (cpp): cpu_capacity needs 40.0% CPU, 30.0% CPU free"});
  }

  SECTION("a device without the capacity cannot take the demand") {
    Device d = gpp_device("n1:GPP", "n1");
    d.capacity.erase(kMemCapacity);
    auto a = softpkg("a", {ImplSpec("cpp").memory_mib(1)});
    const auto rejections =
        require_rejection(make_plan(domain_state({d}), request_of({component_request("a", a)})));
    CHECK_THAT(to_string(rejections), Catch::Contains("the device has no mem_capacity capacity"));
  }

  SECTION("an unknown (infinite) capacity is not checked, and the plan says so") {
    const auto unknown =
        domain_state({gpp_device("n1:GPP", "n1", 100, std::numeric_limits<double>::infinity())});
    auto a = softpkg("a", {ImplSpec("cpp").memory_mib(1u << 20)}); // 1 TiB
    const Plan plan = require_plan(make_plan(unknown, request_of({component_request("a", a)})));
    CHECK(plan.notes ==
          std::vector<std::string>{"mem_capacity of n1:GPP is not known: not checked"});
  }
}
