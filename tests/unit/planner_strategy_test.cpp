// Unit tests of the placement planner (allocator/planner.hpp), continued from planner_test.cpp:
// the strategies (pack, spread), affinity between partners, determinism, and the
// ResourceAllocator committing and releasing whole plans.
#include "allocator/planner.hpp"
#include "allocator/resource_allocator.hpp"
#include "planner_fixture.hpp"
#include "planner_state.hpp"

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

// 11
// -----------------------------------------------------------------------------------------------
TEST_CASE("planner: strategies, affinity and determinism", "[planner]") {
  const auto state = domain_state({gpp_device("n1:GPP", "n1"), gpp_device("n2:GPP", "n2")});
  auto pkg = softpkg("comp", {ImplSpec("cpp").utilization(0.3)});
  PlanRequest pair = request_of({component_request("a", pkg), component_request("b", pkg)});

  SECTION("pack puts two components on one device, spread on two") {
    // Pack: a on n1 (equal load, first id), then b on the most loaded device that fits: n1.
    const Plan packed = require_plan(make_plan(state, pair, with(Strategy::Pack)));
    CHECK(device_of(packed, "a") == "n1:GPP");
    CHECK(device_of(packed, "b") == "n1:GPP");
    // Spread: b on the least loaded: n2 (0 % < 30 %).
    const Plan spread = require_plan(make_plan(state, pair, with(Strategy::Spread)));
    CHECK(device_of(spread, "a") == "n1:GPP");
    CHECK(device_of(spread, "b") == "n2:GPP");
  }

  SECTION("pack: a connected pair stays on one node") {
    // n2 already carries 50 %; a is assigned to n1. Pack alone sends b to the fuller n2
    // (50 % > 30 %); the affinity a-b keeps it with a on n1.
    DomainState loaded = state;
    loaded["n2:GPP"].load.allocated[kCpuCapacity] = 50;
    pair.components[0].device = "n1:GPP";
    CHECK(device_of(require_plan(make_plan(loaded, pair)), "b") == "n2:GPP");
    pair.affinities.push_back({"a", "b", 1.0});
    CHECK(device_of(require_plan(make_plan(loaded, pair)), "b") == "n1:GPP");
  }

  SECTION("spread: a heavy pair (weight >= 10) stays together, a light one is spread") {
    const auto spread = with(Strategy::Spread);
    pair.affinities.push_back({"a", "b", 1.0});
    CHECK(device_of(require_plan(make_plan(state, pair, spread)), "b") == "n2:GPP");
    pair.affinities[0].weight = 10.0;
    CHECK(device_of(require_plan(make_plan(state, pair, spread)), "b") == "n1:GPP");
  }

  SECTION("spread: a chain lands as runs of neighbours, a fair share per device") {
    // Six in a chain on three devices: two each, neighbours together (2 connections cross
    // devices, not 5 as alternating would give).
    const auto three = domain_state(
        {gpp_device("n1:GPP", "n1"), gpp_device("n2:GPP", "n2"), gpp_device("n3:GPP", "n3")});
    auto light = softpkg("light", {ImplSpec("cpp").utilization(0.01)});
    std::vector<ComponentRequest> chain;
    for (const char *id : {"c1", "c2", "c3", "c4", "c5", "c6"})
      chain.push_back(component_request(id, light));
    PlanRequest request = request_of(chain);
    for (std::size_t k = 1; k < chain.size(); ++k)
      request.affinities.push_back({chain[k - 1].instance, chain[k].instance, 1.0});
    const Plan plan = require_plan(make_plan(three, request, with(Strategy::Spread)));
    CHECK(device_of(plan, "c1") == device_of(plan, "c2"));
    CHECK(device_of(plan, "c3") == device_of(plan, "c4"));
    CHECK(device_of(plan, "c5") == device_of(plan, "c6"));
    const std::set<std::string> used{device_of(plan, "c1"), device_of(plan, "c3"),
                                     device_of(plan, "c5")};
    CHECK(used.size() == 3);
  }

  SECTION("the same input gives the same plan") {
    auto other = softpkg("other", {ImplSpec("qnx").os("QNX"), ImplSpec("linux").utilization(0.2)});
    PlanRequest request = request_of({component_request("a", pkg), component_request("b", other),
                                      periodic("p", pkg, 10, 1), component_request("c", pkg),
                                      component_request("d", other)});
    request.components[0].collocation = request.components[3].collocation = "g";
    request.affinities.push_back({"b", "d", 3.0});
    for (const auto strategy : {Strategy::Pack, Strategy::Spread}) {
      const Plan first = require_plan(make_plan(state, request, with(strategy)));
      const Plan second = require_plan(make_plan(DomainState(state), request, with(strategy)));
      REQUIRE(first.placements.size() == second.placements.size());
      for (std::size_t k = 0; k < first.placements.size(); ++k) {
        const auto &x = first.placements[k];
        const auto &y = second.placements[k];
        CHECK(x.instance == y.instance);
        CHECK(x.device == y.device);
        CHECK(x.implementation == y.implementation);
        CHECK(x.demand == y.demand);
        CHECK(x.schedule.has_value() == y.schedule.has_value());
        if (x.schedule && y.schedule) {
          CHECK(x.schedule->cpu == y.schedule->cpu);
          CHECK(x.schedule->priority == y.schedule->priority);
          CHECK(x.schedule->response_time == y.schedule->response_time);
        }
      }
    }
  }
}

// 12
// -----------------------------------------------------------------------------------------------
TEST_CASE("planner: ResourceAllocator commits whole plans and gives everything back", "[planner]") {
  ResourceAllocator allocator;
  allocator.set_node_devices("n1", {gpp_device("n1:GPP", "n1")});
  allocator.set_node_devices("n2", {gpp_device("n2:GPP", "n2")});
  const DomainState empty = allocator.snapshot();

  // app1: a (60 %, 512 MiB) and p (C=1,T=10: 10 %). Pack: a on n1 (first id), p follows to n1.
  auto big = softpkg("big", {ImplSpec("cpp").utilization(0.6).memory_mib(512)});
  auto tiny = softpkg("tiny", {ImplSpec("cpp")});
  const PlanRequest app1 = request_of({component_request("a", big), periodic("p", tiny, 10, 1)});

  const auto planned = allocator.plan(app1, {});
  REQUIRE(planned.has_value());
  CHECK(rsca::test::same_load(allocator.snapshot(), empty)); // plan() reserves nothing

  const auto first = allocator.allocate(app1, {});
  REQUIRE(first.has_value());
  const DomainState after_first = allocator.snapshot();
  CHECK(allocated(after_first, "n1:GPP", kCpuCapacity) == Approx(70)); // 60 + 10
  CHECK(allocated(after_first, "n1:GPP", kMemCapacity) == 512);
  REQUIRE(after_first.at("n1:GPP").load.cpu_tasks.size() == 1);
  REQUIRE(after_first.at("n1:GPP").load.cpu_tasks[0].size() == 1);
  CHECK(after_first.at("n1:GPP").load.cpu_tasks[0][0].id == "p");

  SECTION("a rejected allocation leaves the state unchanged") {
    // x and y (60 % each) in one group: n1 has 30 % free, n2 100 %: no node takes 120 %.
    PlanRequest app2 = request_of({component_request("x", big), component_request("y", big)});
    app2.components[0].collocation = app2.components[1].collocation = "g";
    CHECK_FALSE(allocator.allocate(app2, {}).has_value());
    CHECK(rsca::test::same_load(allocator.snapshot(), after_first));
  }

  SECTION("release gives everything back") {
    allocator.release(*first);
    const DomainState released = allocator.snapshot();
    for (const auto &[id, s] : released) {
      for (const auto &[name, amount] : s.load.allocated)
        CHECK(amount == Approx(0).margin(1e-9));
      for (const auto &tasks : s.load.cpu_tasks)
        CHECK(tasks.empty());
    }
  }

  SECTION("set_node_devices keeps the load of devices that remain") {
    Device bigger = gpp_device("n1:GPP", "n1", 200, 2048);
    allocator.set_node_devices("n1", {bigger, gpp_device("n1:GPP_2", "n1")});
    const DomainState s = allocator.snapshot();
    REQUIRE(s.size() == 3);
    CHECK(s.at("n1:GPP").device.capacity.at(kCpuCapacity) == 200); // the new description
    CHECK(s.at("n1:GPP").load.allocated == after_first.at("n1:GPP").load.allocated);
    CHECK((s.at("n1:GPP").load.cpu_tasks == after_first.at("n1:GPP").load.cpu_tasks));
    CHECK(s.at("n1:GPP_2").load.allocated.empty());
    CHECK(s.at("n2:GPP").load.allocated == after_first.at("n2:GPP").load.allocated);

    // A device the node no longer announces is gone.
    allocator.set_node_devices("n1", {gpp_device("n1:GPP_2", "n1")});
    CHECK(allocator.snapshot().count("n1:GPP") == 0);
  }

  SECTION("remove_node drops the node's devices and their load") {
    allocator.remove_node("n1");
    const DomainState s = allocator.snapshot();
    REQUIRE(s.size() == 1);
    CHECK(s.count("n2:GPP") == 1);
    allocator.release(*first); // its devices are gone: nothing to give back, nothing breaks
    CHECK(rsca::test::same_load(allocator.snapshot(), s));
  }
}
