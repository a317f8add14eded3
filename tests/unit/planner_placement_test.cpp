// Unit tests of the placement planner (allocator/planner.hpp), continued from planner_test.cpp:
// where components go relative to each other and to devices (host collocation, devicerequires
// and deployerrequires, explicit assignment, usesdevice), every expected value worked out by
// hand in a comment next to it.
#include "allocator/planner.hpp"
#include "planner_fixture.hpp"

#include <catch2/catch.hpp>
#include <fmt/format.h>

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

// 5
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: host collocation keeps a group on one node", "[planner]") {
  const auto state = domain_state({gpp_device("n1:GPP", "n1"), gpp_device("n2:GPP", "n2")});
  const auto spread = with(Strategy::Spread);

  SECTION("a group lands on one node although spreading would separate it") {
    auto pkg = softpkg("comp", {ImplSpec("cpp").utilization(0.3)});
    PlanRequest request = request_of({component_request("a", pkg), component_request("b", pkg)});
    // Without the group: a on n1 (equal load, first id), b on n2 (0 % < 30 %).
    const Plan apart = require_plan(make_plan(state, request, spread));
    CHECK(device_of(apart, "a") == "n1:GPP");
    CHECK(device_of(apart, "b") == "n2:GPP");
    // With it: b follows a to n1 (30 + 30 = 60 % fits).
    request.components[0].collocation = request.components[1].collocation = "g";
    const Plan together = require_plan(make_plan(state, request, spread));
    CHECK(device_of(together, "a") == "n1:GPP");
    CHECK(device_of(together, "b") == "n1:GPP");
  }

  SECTION("a group that fits on no single node is rejected although its members fit apart") {
    auto pkg = softpkg("comp", {ImplSpec("cpp").utilization(0.6)});
    PlanRequest request = request_of({component_request("a", pkg), component_request("b", pkg)});
    CHECK(make_plan(state, request).has_value()); // 60 % on each node
    request.components[0].collocation = request.components[1].collocation = "g";
    // 60 + 60 = 120 % > 100 % on either node.
    const auto rejections = require_rejection(make_plan(state, request));
    CHECK_THAT(to_string(rejections), Catch::Contains("hostcollocation g is on node"));
  }

  SECTION("collocation is per node: a node's two GPPs can share a group") {
    const auto two = domain_state(
        {gpp_device("n1:GPP_1", "n1"), gpp_device("n1:GPP_2", "n1"), gpp_device("n2:GPP", "n2")});
    auto pkg = softpkg("comp", {ImplSpec("cpp").utilization(0.6)});
    PlanRequest request = request_of(
        {component_request("a", pkg), component_request("b", pkg), component_request("free", pkg)});
    request.components[0].collocation = request.components[1].collocation = "g";
    const Plan plan = require_plan(make_plan(two, request));
    // a and b need 60 % each: one per GPP of n1; "free" is not in the group and takes n2.
    CHECK(placement_of(plan, "a").node == "n1");
    CHECK(placement_of(plan, "b").node == "n1");
    CHECK(device_of(plan, "a") != device_of(plan, "b"));
    CHECK(device_of(plan, "free") == "n2:GPP");
  }
}

// 6
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: devicerequires and deployerrequires", "[planner]") {
  // n2:GPP offers (deployerrequires) safety=asil-b; n1:GPP offers nothing. Equal load, so pack
  // would take n1:GPP first for anything.
  Device offering = gpp_device("n2:GPP", "n2");
  offering.deployer_requires["safety"] = "asil-b";
  const auto state = domain_state({gpp_device("n1:GPP", "n1"), offering});
  auto pkg = softpkg("comp", {ImplSpec("cpp")});

  SECTION("a component that requires goes only to the device that offers") {
    ComponentRequest c = component_request("c", pkg);
    c.device_requires.push_back(ref("safety", "asil-b"));
    const Plan plan = require_plan(make_plan(state, request_of({c})));
    CHECK(device_of(plan, "c") == "n2:GPP");

    const auto rejections =
        require_rejection(make_plan(domain_state({gpp_device("n1:GPP", "n1")}), request_of({c})));
    CHECK(rejections[0].reasons ==
          std::vector<std::string>{"n1:GPP (cpp): devicerequires safety=asil-b, the device's "
                                   "deployerrequires do not offer it"});

    c.device_requires[0] = ref("safety", "asil-d"); // offered nowhere
    CHECK_FALSE(make_plan(state, request_of({c})).has_value());
  }

  SECTION("a device that offers refuses a component that does not require it") {
    const Plan plan = require_plan(make_plan(state, request_of({component_request("c", pkg)})));
    CHECK(device_of(plan, "c") == "n1:GPP");

    const auto rejections = require_rejection(
        make_plan(domain_state({offering}), request_of({component_request("c", pkg)})));
    CHECK(rejections[0].reasons ==
          std::vector<std::string>{"n2:GPP (cpp): deployerrequires safety=asil-b: the device takes "
                                   "only components that require it"});
  }
}

// 7
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: explicit assignment", "[planner]") {
  const auto state =
      domain_state({gpp_device("n1:GPP", "n1"), gpp_device("n2:GPP", "n2", 100, 1024, "QNX")});
  auto pkg = softpkg("comp", {ImplSpec("cpp")});
  ComponentRequest c = component_request("c", pkg);

  SECTION("honoured over the strategy's preference") {
    c.device = "n2:GPP"; // pack would take n1:GPP (equal load, first id)
    const Plan plan = require_plan(make_plan(state, request_of({c})));
    CHECK(device_of(plan, "c") == "n2:GPP");
  }

  SECTION("an unknown device is rejected") {
    c.device = "n9:GPP";
    const auto rejections = require_rejection(make_plan(state, request_of({c})));
    REQUIRE(rejections.size() == 1);
    CHECK(rejections[0].instance == "c");
    CHECK(rejections[0].reasons ==
          std::vector<std::string>{"the assigned device n9:GPP is not in the domain"});
  }

  SECTION("an assigned device that cannot run it is rejected, though another could") {
    auto linux_only = softpkg("comp", {ImplSpec("cpp").os("Linux")});
    ComponentRequest l = component_request("c", linux_only);
    l.device = "n2:GPP";
    const auto rejections = require_rejection(make_plan(state, request_of({l})));
    CHECK(rejections[0].reasons ==
          std::vector<std::string>{"n2:GPP (cpp): os_name is QNX, implementation cpp needs Linux"});
  }
}

// 8
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: usesdevice places on the used device's node and allocates it", "[planner]") {
  // n2 has a camera with one channel; n1 has none.
  const Device camera = peripheral(
      "n2:camera", "n2", {{"model", "model", "imx219", profile::Action::Eq}}, {{"channels", 1.0}});
  const auto state = domain_state({gpp_device("n1:GPP", "n1"), gpp_device("n2:GPP", "n2"), camera});
  const auto cam = uses_device("cam", {ref("model", "imx219"), ref("channels", "1")});
  auto pkg = softpkg("comp", {ImplSpec("cpp").uses(cam)});

  SECTION("placed on the GPP of the camera's node, the channel reserved") {
    const Plan plan = require_plan(make_plan(state, request_of({component_request("c", pkg)})));
    const Placement &p = placement_of(plan, "c");
    CHECK(p.device == "n2:GPP"); // n1 has no device with model imx219
    REQUIRE(p.used_devices.size() == 1);
    CHECK(p.used_devices[0].uses_id == "cam");
    CHECK(p.used_devices[0].device == "n2:camera");
    CHECK(p.used_devices[0].demand == std::map<std::string, double>{{"channels", 1.0}});
    DomainState committed = state;
    commit(committed, plan);
    CHECK(allocated(committed, "n2:camera", "channels") == 1);
    // The channel is taken: the same component again does not fit.
    CHECK_FALSE(make_plan(committed, request_of({component_request("c", pkg)})).has_value());
  }

  SECTION("a second component needing the single channel is rejected") {
    const auto rejections = require_rejection(
        make_plan(state, request_of({component_request("c1", pkg), component_request("c2", pkg)})));
    CHECK(rejections[0].instance == "c2");
    CHECK_THAT(to_string(rejections),
               Catch::Contains("usesdevice cam: no device in the domain fits"));
  }

  SECTION("a device on a node without a GPP is used across the network") {
    const Device sensor = peripheral("robot:sensor", "robot",
                                     {{"model", "model", "imx219", profile::Action::Eq}}, {});
    const auto remote = domain_state({gpp_device("n1:GPP", "n1"), sensor});
    const Plan plan = require_plan(
        make_plan(remote, request_of({component_request(
                              "c", softpkg("comp", {ImplSpec("cpp").uses(uses_device(
                                                       "cam", {ref("model", "imx219")}))}))})));
    const Placement &p = placement_of(plan, "c");
    CHECK(p.device == "n1:GPP");
    REQUIRE(p.used_devices.size() == 1);
    CHECK(p.used_devices[0].device == "robot:sensor");
  }

  SECTION("two usesdevice of one implementation cannot both take the single channel") {
    // 1 + 1 = 2 channels wanted of a camera that has 1: accepting would over-commit it.
    auto twice = softpkg("stereo", {ImplSpec("cpp")
                                        .uses(uses_device("left", {ref("channels", "1")}))
                                        .uses(uses_device("right", {ref("channels", "1")}))});
    const auto result = make_plan(state, request_of({component_request("s", twice)}));
    if (result) {
      DomainState committed = state;
      commit(committed, *result);
      INFO("camera channels allocated: " << allocated(committed, "n2:camera", "channels"));
      CHECK(allocated(committed, "n2:camera", "channels") <= 1.0);
    }
    CHECK_FALSE(result.has_value());
  }

  SECTION("the application's own usesdevice is reserved in application_devices") {
    auto plain = softpkg("plain", {ImplSpec("cpp")});
    PlanRequest request = request_of({component_request("c", plain)});
    request.uses_devices.push_back(cam);
    const Plan plan = require_plan(make_plan(state, request));
    REQUIRE(plan.application_devices.size() == 1);
    CHECK(plan.application_devices[0].device == "n2:camera");
    CHECK(plan.application_devices[0].demand == std::map<std::string, double>{{"channels", 1.0}});
  }

  SECTION("a failed application usesdevice does not leak what an earlier one reserved") {
    // n1: GPP + radio (band s, 1 slot); n2: GPP + radio (band x, 1 slot) + the camera.
    // Component c uses any radio slot on its node. The application uses the camera channel
    // ("cam") and a band-s radio slot ("uplink", only n1:radio has band s).
    // The one plan: c on n2:GPP with n2:radio; cam -> n2:camera, uplink -> n1:radio.
    // The search first tries c on n1:GPP (pack, equal load, first id), which takes n1:radio's
    // slot: cam is then reserved, uplink fails. Backtracking to n2:GPP must find the camera free.
    const Device radio1 = peripheral("n1:radio", "n1", {{"band", "band", "s", profile::Action::Eq}},
                                     {{"slots", 1.0}});
    const Device radio2 = peripheral("n2:radio", "n2", {{"band", "band", "x", profile::Action::Eq}},
                                     {{"slots", 1.0}});
    const auto radios = domain_state(
        {gpp_device("n1:GPP", "n1"), radio1, gpp_device("n2:GPP", "n2"), radio2, camera});
    auto linked =
        softpkg("linked", {ImplSpec("cpp").uses(uses_device("link", {ref("slots", "1")}))});
    PlanRequest request = request_of({component_request("c", linked)});
    request.uses_devices = {cam, uses_device("uplink", {ref("band", "s"), ref("slots", "1")})};
    // The plan exists: pinned to n2:GPP (so the search never tries n1), it is found.
    PlanRequest pinned = request;
    pinned.components[0].device = "n2:GPP";
    CHECK(make_plan(radios, pinned).has_value());
    const Plan plan = require_plan(make_plan(radios, request));
    CHECK(device_of(plan, "c") == "n2:GPP");
    REQUIRE(plan.application_devices.size() == 2);
    CHECK(plan.application_devices[0].device == "n2:camera");
    CHECK(plan.application_devices[1].device == "n1:radio");
  }
}

// REDHAWK 2.2's hostcollocation children, each worked out by hand.
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: a hostcollocation's cpucores reservation is a floor on its CPU charge",
          "[planner][redhawk22]") {
  // Each GPP has 100 % of cpu_capacity (one core).
  const auto state = domain_state({gpp_device("n1:GPP", "n1"), gpp_device("n2:GPP", "n2")});
  auto pkg = softpkg("comp", {ImplSpec("cpp").utilization(0.2)});
  PlanRequest request = request_of({component_request("a", pkg), component_request("b", pkg)});
  request.components[0].collocation = request.components[1].collocation = "g";

  SECTION("the last member placed is charged up to the reservation") {
    // Members 20 + 20 = 40 %; reservation 0.7 cores = 70 %: the last one is charged 20 + 30.
    request.collocations.push_back({"g", 70.0, {}});
    const Plan plan = require_plan(make_plan(state, request));
    const double a = placement_of(plan, "a").demand.at(kCpuCapacity);
    const double b = placement_of(plan, "b").demand.at(kCpuCapacity);
    CHECK(a + b == Approx(70.0));
    CHECK(std::min(a, b) == Approx(20.0));
    DomainState committed = state;
    commit(committed, plan);
    CHECK(allocated(committed, device_of(plan, "a"), kCpuCapacity) == Approx(70.0));
    release(committed, plan);
    CHECK(allocated(committed, device_of(plan, "a"), kCpuCapacity) == Approx(0.0));
  }
  SECTION("members that demand more than the reservation are charged their own demand") {
    request.collocations.push_back({"g", 30.0, {}}); // 40 % > 30 %
    const Plan plan = require_plan(make_plan(state, request));
    CHECK(placement_of(plan, "a").demand.at(kCpuCapacity) == Approx(20.0));
    CHECK(placement_of(plan, "b").demand.at(kCpuCapacity) == Approx(20.0));
  }
  SECTION("a reservation no node can hold is rejected, saying so") {
    request.collocations.push_back({"g", 150.0, {}}); // 1.5 cores on one-core nodes
    const auto rejections = require_rejection(make_plan(state, request));
    CHECK_THAT(to_string(rejections), Catch::Contains("hostcollocation g reserves 1.5 cores"));
  }
  SECTION("a reservation that fits only on the emptier node goes there") {
    DomainState busy = state;
    busy.at("n1:GPP").load.allocated[kCpuCapacity] = 50.0; // n1 has 50 % left
    request.collocations.push_back({"g", 80.0, {}});
    const Plan plan = require_plan(make_plan(busy, request));
    CHECK(placement_of(plan, "a").node == "n2");
    CHECK(placement_of(plan, "b").node == "n2");
    // Charged 80 % together although n1 was tried first (and left: 50 % free).
    CHECK(placement_of(plan, "a").demand.at(kCpuCapacity) +
              placement_of(plan, "b").demand.at(kCpuCapacity) ==
          Approx(80.0));
  }
}

TEST_CASE("planner: a hostcollocation's usesdeviceref puts it next to that device",
          "[planner][redhawk22]") {
  // The radio is on n2; the application uses it (SAD usesdevice "radio"); the collocation that
  // refers to it must be on n2 although packing would put it on n1.
  const Device radio =
      peripheral("n2:radio", "n2", {{"kind", "kind", "radio", profile::Action::Eq}}, {});
  const auto state = domain_state({gpp_device("n1:GPP", "n1"), gpp_device("n2:GPP", "n2"), radio});
  auto pkg = softpkg("comp", {ImplSpec("cpp").utilization(0.1)});
  PlanRequest request = request_of({component_request("a", pkg), component_request("b", pkg)});
  request.uses_devices.push_back(uses_device("radio", {ref("kind", "radio")}));

  SECTION("without usesdeviceref packing fills n1") {
    const Plan plan = require_plan(make_plan(state, request));
    CHECK(placement_of(plan, "a").node == "n1");
    REQUIRE(plan.application_devices.size() == 1);
    CHECK(plan.application_devices[0].device == "n2:radio");
  }
  SECTION("with it the collocation goes to the radio's node") {
    request.components[0].collocation = request.components[1].collocation = "g";
    request.collocations.push_back({"g", 0.0, {"radio"}});
    const Plan plan = require_plan(make_plan(state, request));
    CHECK(placement_of(plan, "a").node == "n2");
    CHECK(placement_of(plan, "b").node == "n2");
    CHECK(plan.application_devices[0].device == "n2:radio");
  }
  SECTION("two collocations tied to one device on different nodes are rejected") {
    auto big = softpkg("big", {ImplSpec("cpp").utilization(0.6)});
    PlanRequest two = request_of({component_request("a", big), component_request("b", big)});
    two.uses_devices.push_back(uses_device("radio", {ref("kind", "radio")}));
    two.components[0].collocation = "g1";
    two.components[1].collocation = "g2";
    two.collocations = {{"g1", 0.0, {"radio"}}, {"g2", 0.0, {"radio"}}};
    // 60 + 60 % cannot share a one-core node; apart they are on two nodes, one of them not
    // the radio's.
    const auto rejections = require_rejection(make_plan(state, two));
    CHECK_THAT(to_string(rejections), Catch::Contains("usesdevice radio"));
  }
  SECTION("a node without the device is left at once, not after the rest is placed") {
    // Six nodes, the radio on n6, the collocation first in order (fewest candidates), and ten
    // more components of two implementations each: searching every placement of those under
    // a collocation on the wrong node would take far more than this budget.
    std::vector<Device> devices;
    for (int n = 1; n <= 6; ++n)
      devices.push_back(gpp_device(fmt::format("n{}:GPP", n), fmt::format("n{}", n)));
    devices.push_back(
        peripheral("n6:radio", "n6", {{"kind", "kind", "radio", profile::Action::Eq}}, {}));
    const auto six = domain_state(devices);
    auto light =
        softpkg("light", {ImplSpec("a").utilization(0.05), ImplSpec("b").utilization(0.05)});
    std::vector<ComponentRequest> components{component_request("a", pkg),
                                             component_request("b", pkg)};
    for (int k = 0; k < 10; ++k)
      components.push_back(component_request(fmt::format("x{}", k), light));
    PlanRequest wide = request_of(components);
    wide.uses_devices.push_back(uses_device("radio", {ref("kind", "radio")}));
    wide.components[0].collocation = wide.components[1].collocation = "g";
    wide.collocations.push_back({"g", 0.0, {"radio"}});
    PlanOptions small = with(Strategy::Pack);
    small.budget = 100;
    const Plan plan = require_plan(make_plan(six, wide, small));
    CHECK(placement_of(plan, "a").node == "n6");
    CHECK(placement_of(plan, "b").node == "n6");
  }
}
