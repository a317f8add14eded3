// Unit tests of the placement planner (allocator/planner.hpp), continued from planner_test.cpp:
// timing admission on each CPU of a device and end-to-end latency paths, every expected value
// worked out by hand in a comment next to it.
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

// 9
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: timing admission per CPU", "[planner]") {
  auto pkg = softpkg("comp", {ImplSpec("cpp")});
  // a (C=2,T=5), b (C=2,T=7), c (C=2,T=7): U = 0.4 + 0.286 + 0.286 = 0.971 <= 1 and the CPU
  // demand 40 + 28.6 + 28.6 = 97.1 % fits 100 %, so only the response-time analysis decides.
  // Deadline monotonic: a highest, then b, then c (same D and T as b, later in input order).
  //   R_a = 2; R_b = 2 + 2 = 4 <= 7;
  //   R_c: w = 2 + 2 + 2 = 6, w = 2 + ceil(6/5)*2 + ceil(6/7)*2 = 8 > 7: misses.
  const PlanRequest three =
      request_of({periodic("a", pkg, 5, 2), periodic("b", pkg, 7, 2), periodic("c", pkg, 7, 2)});

  SECTION("fixed priority, one CPU: the third task breaks RTA and is rejected") {
    const auto state = domain_state({gpp_device("n1:GPP", "n1")});
    CHECK(make_plan(state, request_of({three.components[0], three.components[1]})).has_value());
    const auto rejections = require_rejection(make_plan(state, three));
    REQUIRE(rejections.size() == 1);
    CHECK(rejections[0].instance == "c");
    CHECK_THAT(to_string(rejections), Catch::Contains("timing admission failed on every CPU") &&
                                          Catch::Contains("task c") &&
                                          Catch::Contains("exceeds its deadline 7ms"));
  }

  SECTION("two CPUs: the third task goes to the second CPU, with its schedule") {
    Device d = gpp_device("n1:GPP", "n1", 200);
    d.cpus = 2;
    const Plan plan = require_plan(make_plan(domain_state({d}), three));
    // Pack fills the most loaded CPU first: a and b on CPU 0, c does not fit there -> CPU 1.
    const auto &sa = placement_of(plan, "a").schedule;
    const auto &sb = placement_of(plan, "b").schedule;
    const auto &sc = placement_of(plan, "c").schedule;
    REQUIRE((sa && sb && sc));
    CHECK(sa->cpu == 0);
    CHECK(sb->cpu == 0);
    // b is the lower of CPU 0's two tasks: priority 1, R_b = 4 ms.
    CHECK(sb->priority == 1);
    CHECK(sb->response_time == milliseconds{4});
    // c alone on CPU 1: priority 1 (the least urgent gets 1), R = C = 2 ms.
    CHECK(sc->cpu == 1);
    CHECK(sc->policy == SchedulingPolicy::FixedPriority);
    CHECK(sc->priority == 1);
    CHECK(sc->period == milliseconds{7});
    CHECK(sc->budget == milliseconds{2});
    CHECK(sc->deadline == milliseconds{7});
    CHECK(sc->response_time == milliseconds{2});
    // The periodic demand is also CPU capacity: 100 * C / T = 40 %.
    CHECK(placement_of(plan, "a").demand.at(kCpuCapacity) == Approx(40));
  }

  SECTION("EDF admits a set fixed priority rejects") {
    // (C=2,T=5), (C=4,T=7): U = 2/5 + 4/7 = 34/35 <= 1 -> EDF schedulable.
    // FP: R_b: w = 4 + 2 = 6, w = 4 + ceil(6/5)*2 = 8 > 7 -> misses.
    const PlanRequest pair = request_of({periodic("a", pkg, 5, 2), periodic("b", pkg, 7, 4)});
    const auto fp = require_rejection(make_plan(domain_state({gpp_device("n1:GPP", "n1")}), pair));
    CHECK_THAT(to_string(fp), Catch::Contains("task b"));

    Device edf = gpp_device("n1:GPP", "n1");
    edf.policy = SchedulingPolicy::Edf;
    const Plan plan = require_plan(make_plan(domain_state({edf}), pair));
    const auto &sb = placement_of(plan, "b").schedule;
    REQUIRE(sb);
    CHECK(sb->policy == SchedulingPolicy::Edf);
    CHECK(sb->priority == 0);                    // EDF has no priorities
    CHECK(sb->response_time == milliseconds{7}); // EDF guarantees the deadline
    CHECK(sb->budget == milliseconds{4});
  }

  SECTION("an earlier component's schedule reflects later admissions on its CPU") {
    // x (C=1,T=4) is placed first, alone: priority 1. Then y (C=10,T=100) joins the CPU and
    // the analysis of {x, y} ranks x above y (deadline monotonic): x 2, y 1;
    // R_x = 1, R_y: w = 10 + 1 = 11 -> 10 + ceil(11/4)*1 = 13 -> 10 + 4 = 14 -> 14 <= 100.
    // x must be delivered priority 2: at priority 1 it ties with y and can wait for y's 10 ms
    // (R_x = 1 + 10 = 11 > 4), a deadline miss the admission never checked.
    const auto state = domain_state({gpp_device("n1:GPP", "n1")});
    const Plan plan = require_plan(
        make_plan(state, request_of({periodic("x", pkg, 4, 1), periodic("y", pkg, 100, 10)})));
    const auto &sx = placement_of(plan, "x").schedule;
    const auto &sy = placement_of(plan, "y").schedule;
    REQUIRE((sx && sy));
    CHECK(sx->priority > sy->priority);
    CHECK(sy->response_time == milliseconds{14});
    // What is committed is what gets deployed: it must pass the same analysis.
    DomainState committed = state;
    commit(committed, plan);
    const auto verdict =
        analyse(committed.at("n1:GPP").load.cpu_tasks.at(0), SchedulingPolicy::FixedPriority);
    INFO(verdict.reason);
    CHECK(verdict.schedulable);
  }
}

// 10
// -----------------------------------------------------------------------------------------------
TEST_CASE("planner: end-to-end latency paths", "[planner]") {
  auto pkg = softpkg("comp", {ImplSpec("cpp")});
  const auto state = domain_state({gpp_device("n1:GPP", "n1")});
  // One CPU, a (C=2,T=10) above b (C=3,T=20): R_a = 2; R_b: w = 3 + 2 = 5 -> 3 + ceil(5/10)*2 = 5.
  // Path a -> b: R_a + (T_b + R_b) = 2 + 20 + 5 = 27 ms.
  PlanRequest request = request_of({periodic("a", pkg, 10, 2), periodic("b", pkg, 20, 3)});

  SECTION("a bound equal to the worst case is met") {
    request.latency_paths.push_back(latency_path("p", 27, {"a", "b"}));
    const Plan plan = require_plan(make_plan(state, request));
    CHECK(placement_of(plan, "b").schedule->response_time == milliseconds{5});
  }

  SECTION("a bound below the worst case rejects the application, naming the path") {
    request.latency_paths.push_back(latency_path("p", 26, {"a", "b"}));
    const auto rejections = require_rejection(make_plan(state, request));
    REQUIRE(rejections.size() == 1);
    CHECK(rejections[0].instance == "(application)");
    CHECK(rejections[0].reasons ==
          std::vector<std::string>{"latency path p: worst case 27ms exceeds its bound 26ms"});
  }

  SECTION("the worst case uses response times of the final task set") {
    // b is listed (and placed) first: alone its response is 3 ms. Then a joins the CPU above
    // it, and R_b becomes 5 ms. Path b -> a: R_b + (T_a + R_a) = 5 + 10 + 2 = 17 ms > 16 ms.
    // (With the stale R_b = 3 it would be 15 ms and wrongly accepted.)
    PlanRequest reversed = request_of({request.components[1], request.components[0]});
    reversed.latency_paths.push_back(latency_path("q", 16, {"b", "a"}));
    const auto result = make_plan(state, reversed);
    if (result)
      CHECK(placement_of(*result, "b").schedule->response_time == milliseconds{5});
    CHECK_FALSE(result.has_value());
  }
}
