#include "allocator/schedulability.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <limits>
#include <numeric>
#include <optional>
#include <random>
#include <string>
#include <vector>

using namespace rsca::allocator;
using namespace std::chrono_literals;

namespace {

using std::chrono::milliseconds;

// A task in milliseconds; the deadline defaults to the period.
Task task(std::string id, std::int64_t period, std::int64_t execution,
          std::optional<std::int64_t> deadline = std::nullopt,
          std::optional<std::uint32_t> priority = std::nullopt) {
  return Task{std::move(id), milliseconds{period}, milliseconds{execution},
              milliseconds{deadline.value_or(period)}, priority};
}

std::vector<std::int64_t> response_ms(const Schedulability &result) {
  std::vector<std::int64_t> out;
  for (const auto &verdict : result.tasks)
    out.push_back(std::chrono::duration_cast<milliseconds>(verdict.response_time).count());
  return out;
}

std::vector<std::uint32_t> priorities(const Schedulability &result) {
  std::vector<std::uint32_t> out;
  for (const auto &verdict : result.tasks)
    out.push_back(verdict.priority);
  return out;
}

std::vector<bool> meets(const Schedulability &result) {
  std::vector<bool> out;
  for (const auto &verdict : result.tasks)
    out.push_back(verdict.meets_deadline);
  return out;
}

std::vector<std::string> ids(const Schedulability &result) {
  std::vector<std::string> out;
  for (const auto &verdict : result.tasks)
    out.push_back(verdict.id);
  return out;
}

constexpr auto kFp = SchedulingPolicy::FixedPriority;
constexpr auto kEdf = SchedulingPolicy::Edf;

} // namespace

TEST_CASE("schedulability: Audsley's classic set meets its deadlines under deadline monotonic",
          "[schedulability]") {
  // U = 3/7 + 3/12 + 5/20 = 0.4286 + 0.25 + 0.25 = 0.9286, above the n=3 bound 0.7798.
  const std::vector<Task> tasks{task("a", 7, 3), task("b", 12, 3), task("c", 20, 5)};
  const auto result = analyse(tasks, kFp);
  INFO(result.reason);
  CHECK(result.schedulable);
  CHECK(result.reason.empty());
  CHECK(result.utilization == Approx(0.928571).epsilon(1e-5));
  // a: R = 3 (nothing above it).
  // b: R = 3 -> 3 + ceil(3/7)*3 = 6 -> 3 + ceil(6/7)*3 = 6.
  // c: R = 5 -> 5 + ceil(5/7)*3 + ceil(5/12)*3 = 11 -> 5 + 2*3 + 1*3 = 14 -> 5 + 2*3 + 2*3 = 17
  //      -> 5 + 3*3 + 2*3 = 20 -> 5 + 3*3 + 2*3 = 20, exactly at its deadline.
  CHECK(response_ms(result) == std::vector<std::int64_t>{3, 6, 20});
  CHECK(meets(result) == std::vector<bool>{true, true, true});
  // Deadline monotonic, counting down to 1 for the least urgent.
  CHECK(priorities(result) == std::vector<std::uint32_t>{3, 2, 1});
}

TEST_CASE("schedulability: Audsley's set with a longer third task misses its deadline",
          "[schedulability]") {
  // U = 3/7 + 3/12 + 6/20 = 0.9786: still under 1, so response-time analysis decides.
  const std::vector<Task> tasks{task("a", 7, 3), task("b", 12, 3), task("c", 20, 6)};
  const auto result = analyse(tasks, kFp);
  CHECK_FALSE(result.schedulable);
  // c: R = 6 -> 6 + ceil(6/7)*3 + ceil(6/12)*3 = 12 -> 6 + 2*3 + 1*3 = 15 -> 6 + 3*3 + 2*3 = 21
  //      > 20: stop.
  CHECK(result.reason ==
        "task c: worst-case response at least 21ms exceeds its deadline 20ms (utilization 0.98)");
  CHECK(response_ms(result) == std::vector<std::int64_t>{3, 6, 21});
  CHECK(meets(result) == std::vector<bool>{true, true, false});
}

TEST_CASE("schedulability: Liu and Layland bound is sufficient, not necessary",
          "[schedulability]") {
  CHECK(liu_layland_bound(1) == Approx(1.0));
  CHECK(liu_layland_bound(2) == Approx(0.828427).epsilon(1e-5));    // 2(sqrt 2 - 1)
  CHECK(liu_layland_bound(3) == Approx(0.779763).epsilon(1e-5));    // 3(2^(1/3) - 1)
  CHECK(liu_layland_bound(1000) == Approx(0.693387).epsilon(1e-5)); // tends to ln 2 = 0.693147
  CHECK(liu_layland_bound(0) == 1.0);

  // Harmonic periods: U = 1/2 + 2/4 = 1.0, far above 0.8284, yet
  // a: R = 1; b: R = 2 -> 2 + ceil(2/2)*1 = 3 -> 2 + ceil(3/2)*1 = 4 -> 4 <= 4.
  const std::vector<Task> tasks{task("a", 2, 1), task("b", 4, 2)};
  const auto result = analyse(tasks, kFp);
  CHECK(result.utilization > liu_layland_bound(2));
  CHECK(result.schedulable);
  CHECK(response_ms(result) == std::vector<std::int64_t>{1, 4});
}

TEST_CASE("schedulability: full load is judged exactly, not in floating point",
          "[schedulability]") {
  // U = 1/2 + 1/3 + 1/6 = 1 exactly.
  const std::vector<Task> tasks{task("a", 2, 1), task("b", 3, 1), task("c", 6, 1)};
  const auto edf = analyse(tasks, kEdf);
  CHECK(edf.schedulable);
  // EDF reports each deadline as its response bound.
  CHECK(response_ms(edf) == std::vector<std::int64_t>{2, 3, 6});
  CHECK(priorities(edf) == std::vector<std::uint32_t>{0, 0, 0});

  // Rate monotonic also makes it: c: R = 1 -> 1 + 1 + 1 = 3 -> 1 + 2 + 1 = 4 -> 1 + 2 + 2 = 5
  // -> 1 + 3 + 2 = 6 -> 6 (= its deadline).
  const auto fp = analyse(tasks, kFp);
  CHECK(fp.schedulable);
  CHECK(response_ms(fp) == std::vector<std::int64_t>{1, 2, 6});
}

TEST_CASE("schedulability: EDF with implicit deadlines is schedulable up to full load",
          "[schedulability]") {
  CHECK(analyse({task("a", 2, 1), task("b", 4, 2)}, kEdf).schedulable); // U = 1.0

  // U = 1/2 + 1/3 + 1/5 = 1.033.
  const auto over = analyse({task("a", 2, 1), task("b", 3, 1), task("c", 5, 1)}, kEdf);
  CHECK_FALSE(over.schedulable);
  CHECK(over.reason == "utilization 1.03 exceeds 1: the processor cannot keep up");
  CHECK(meets(over) == std::vector<bool>{false, false, false});

  // One nanosecond too much: U = 1 + 1e-7, printed with the digits that show it.
  const auto barely =
      analyse({Task{"a", 10ms, 5ms, 10ms, {}}, Task{"b", 10ms, 5ms + 1ns, 10ms, {}}}, kEdf);
  CHECK_FALSE(barely.schedulable);
  CHECK(barely.reason == "utilization 1.0000001 exceeds 1: the processor cannot keep up");
  // The same overload fails fixed priority without response-time analysis.
  const auto barely_fp =
      analyse({Task{"a", 10ms, 5ms, 10ms, {}}, Task{"b", 10ms, 5ms + 1ns, 10ms, {}}}, kFp);
  CHECK(barely_fp.reason == barely.reason);
}

TEST_CASE("schedulability: EDF with constrained deadlines uses the processor demand",
          "[schedulability]") {
  SECTION("demand exceeds the time at a deadline although U < 1") {
    // U = 2/5 + 2/5 = 0.8. Busy period: 4 -> 2*ceil(4/5) + 2*ceil(4/5) = 4, so L = 4.
    // h(2) = 2 <= 2 (a's first job); h(3) = 2 + 2 = 4 > 3 (b's first job): fails at t = 3.
    const auto result = analyse({task("a", 5, 2, 2), task("b", 5, 2, 3)}, kEdf);
    CHECK_FALSE(result.schedulable);
    CHECK(result.reason == "task b: by its deadline at 3ms after a synchronous release, 4ms of "
                           "work is due, more than the 3ms available (utilization 0.80)");
  }
  SECTION("two tasks due at once") {
    // h(2) = 2 + 2 = 4 > 2; the first task due at t = 2 in input order is named.
    const auto result = analyse({task("a", 4, 2, 2), task("b", 4, 2, 2)}, kEdf);
    CHECK_FALSE(result.schedulable);
    CHECK(result.reason.rfind("task a: by its deadline at 2ms", 0) == 0);
  }
  SECTION("demand fits at every deadline") {
    // L = 4 as above; h(2) = 2 <= 2, h(4) = 4 <= 4.
    const auto result = analyse({task("a", 5, 2, 2), task("b", 5, 2, 4)}, kEdf);
    CHECK(result.schedulable);
    CHECK(response_ms(result) == std::vector<std::int64_t>{2, 4});
    CHECK(meets(result) == std::vector<bool>{true, true});
  }
  SECTION("deadlines beyond the period") {
    // U = 1/2 + 3/4 = 1.25 > 1: even late deadlines cannot absorb an overload.
    CHECK_FALSE(analyse({task("a", 2, 1, 10), task("b", 4, 3, 20)}, kEdf).schedulable);
    // U = 1/2 + 2/4 = 1 with D >= T: schedulable.
    CHECK(analyse({task("a", 2, 1, 3), task("b", 4, 2, 8)}, kEdf).schedulable);
  }
}

TEST_CASE("schedulability: EDF schedules a set that fixed priority cannot", "[schedulability]") {
  // U = 2/5 + 4/7 = 0.9714.
  const std::vector<Task> tasks{task("a", 5, 2), task("b", 7, 4)};
  // Deadline monotonic puts a first. b: R = 4 -> 4 + ceil(4/5)*2 = 6 -> 4 + ceil(6/5)*2 = 8 > 7.
  const auto fp = analyse(tasks, kFp);
  CHECK_FALSE(fp.schedulable);
  CHECK(fp.reason ==
        "task b: worst-case response at least 8ms exceeds its deadline 7ms (utilization 0.97)");
  // Implicit deadlines, U <= 1.
  const auto edf = analyse(tasks, kEdf);
  CHECK(edf.schedulable);
  CHECK(response_ms(edf) == std::vector<std::int64_t>{5, 7});
}

TEST_CASE("schedulability: explicit priorities override deadline monotonic", "[schedulability]") {
  SECTION("a bad explicit order fails a set deadline monotonic schedules") {
    // c above b above a. a: R = 3 -> 3 + ceil(3/12)*3 + ceil(3/20)*5 = 11 > 7.
    const auto result =
        analyse({task("a", 7, 3, {}, 1), task("b", 12, 3, {}, 2), task("c", 20, 5, {}, 3)}, kFp);
    CHECK_FALSE(result.schedulable);
    CHECK(priorities(result) == std::vector<std::uint32_t>{1, 2, 3});
    CHECK(result.reason ==
          "task a: worst-case response at least 11ms exceeds its deadline 7ms (utilization 0.93)");
    // b: R = 3 -> 3 + 5 = 8 -> 3 + 5 = 8 <= 12; c: R = 5.
    CHECK(response_ms(result) == std::vector<std::int64_t>{11, 8, 5});
    CHECK(meets(result) == std::vector<bool>{false, true, true});
  }
  SECTION("the same order given explicitly passes") {
    const auto result =
        analyse({task("a", 7, 3, {}, 30), task("b", 12, 3, {}, 20), task("c", 20, 5, {}, 10)}, kFp);
    CHECK(result.schedulable);
    CHECK(response_ms(result) == std::vector<std::int64_t>{3, 6, 20});
  }
  SECTION("unprioritised tasks rank below every explicit priority") {
    // c is given 5; a and b get 4 and 3 by deadline monotonic, so c preempts both.
    // a: R = 3 -> 3 + ceil(3/20)*5 = 8 > 7.
    const auto result = analyse({task("a", 7, 3), task("b", 12, 3), task("c", 20, 5, {}, 5)}, kFp);
    CHECK(ids(result) == std::vector<std::string>{"a", "b", "c"});
    CHECK(priorities(result) == std::vector<std::uint32_t>{4, 3, 5});
    CHECK_FALSE(result.schedulable);
    CHECK(result.reason.rfind("task a: worst-case response at least 8ms", 0) == 0);
  }
  SECTION("deadline monotonic breaks ties by period, then input order") {
    const auto result = analyse(
        {task("a", 12, 1, 6), task("b", 10, 1, 6), task("c", 10, 1, 6), task("d", 20, 1, 5)}, kFp);
    // d (D 5), then b and c (D 6, T 10, input order), then a (D 6, T 12).
    CHECK(priorities(result) == std::vector<std::uint32_t>{1, 3, 2, 4});
  }
  SECTION("no room below the lowest explicit priority: numbers saturate at 0 and are shared") {
    // c is 1; a and b would be 0 and -1, so both get 0 and interfere with each other.
    // a: R = 3 -> 3 + ceil(3/12)*3 + ceil(3/20)*5 = 11 > 7.
    const auto result = analyse({task("a", 7, 3), task("b", 12, 3), task("c", 20, 5, {}, 1)}, kFp);
    CHECK(priorities(result) == std::vector<std::uint32_t>{0, 0, 1});
    CHECK_FALSE(result.schedulable);
    CHECK(result.reason.rfind("task a: worst-case response at least 11ms", 0) == 0);
  }
}

TEST_CASE("schedulability: tasks sharing a priority interfere both ways", "[schedulability]") {
  // Distinct priorities: a: R = 3 <= 4; b: R = 3 + 3 = 6 <= 6.
  CHECK(analyse({task("a", 10, 3, 4, 2), task("b", 10, 3, 6, 1)}, kFp).schedulable);
  // Same priority: either may run first, so a: R = 3 + ceil(3/10)*3 = 6 > 4.
  const auto tied = analyse({task("a", 10, 3, 4, 1), task("b", 10, 3, 6, 1)}, kFp);
  CHECK_FALSE(tied.schedulable);
  CHECK(meets(tied) == std::vector<bool>{false, true});
}

TEST_CASE("schedulability: fixed priority with deadlines beyond the period", "[schedulability]") {
  // Lehoczky's example shape: a (T=70, C=26) above b (T=100, C=62, D=120).
  // U = 26/70 + 62/100 = 0.9914.
  // Job 1 of b: w = 62 -> 62 + 26 = 88 -> 62 + 2*26 = 114 -> 114; R = 114 > T = 100, so job 2
  // is in the same busy period.
  // Job 2: w = 114 + 62 = 176 -> 124 + ceil(176/70)*26 = 202 -> 124 + 3*26 = 202; R = 202 - 100
  // = 102 > 100 again.
  // Job 3: w = 202 + 62 = 264 -> 186 + ceil(264/70)*26 = 290 -> 186 + 5*26 = 316 -> 316;
  // R = 316 - 200 = 116 <= 120, still past the next release (300).
  // Job 4: w = 316 + 62 = 378 -> 248 + 6*26 = 404 -> 248 + 6*26 = 404; R = 404 - 300 = 104;
  // job 5 starts in the busy period too (404 > 400).
  // Job 5: w = 404 + 62 = 466 -> 310 + 7*26 = 492 -> 310 + 8*26 = 518 -> 518; R = 118.
  // Job 6: w = 580 -> 372 + 9*26 = 606 -> 606; R = 106.
  // Job 7: w = 668 -> 434 + 10*26 = 694 -> 694; R = 94 and 694 <= 700: the busy period ends.
  // Worst: 118 (job 5) <= 120.
  const auto result = analyse({task("a", 70, 26), task("b", 100, 62, 120)}, kFp);
  INFO(result.reason);
  CHECK(result.schedulable);
  CHECK(response_ms(result) == std::vector<std::int64_t>{26, 118});

  // With D = 115, job 3 (116) misses although job 1 (114) does not.
  const auto tighter = analyse({task("a", 70, 26), task("b", 100, 62, 115)}, kFp);
  CHECK_FALSE(tighter.schedulable);
  CHECK(tighter.reason == "task b: worst-case response at least 116ms exceeds its deadline 115ms "
                          "(job 3 of a busy period; utilization 0.99)");
}

TEST_CASE("schedulability: invalid tasks are reported, not thrown", "[schedulability]") {
  for (auto policy : {kFp, kEdf}) {
    INFO(to_string(policy));
    const auto zero_period =
        analyse({task("a", 10, 1), Task{"b", 0ms, 1ms, 10ms, {}}, task("c", 5, 1)}, policy);
    CHECK_FALSE(zero_period.schedulable);
    CHECK(zero_period.reason == "task b: period must be positive, got 0s");
    CHECK(ids(zero_period) == std::vector<std::string>{"a", "b", "c"});
    CHECK(meets(zero_period) == std::vector<bool>{false, false, false});
    CHECK(zero_period.utilization == Approx(0.3)); // b contributes nothing

    CHECK(analyse({Task{"x", 10ms, -1ms, 10ms, {}}}, policy).reason ==
          "task x: execution time must be positive, got -1ms");
    CHECK(analyse({Task{"y", 10ms, 1ms, 0ms, {}}}, policy).reason ==
          "task y: deadline must be positive, got 0s");
  }
  // Deadline monotonic priorities are still reported for an invalid set.
  const auto result =
      analyse({task("a", 10, 1), Task{"b", 0ms, 1ms, 10ms, {}}, task("c", 5, 1)}, kFp);
  // c (D 5), then b and a (D 10) by period: b's 0 is shorter.
  CHECK(priorities(result) == std::vector<std::uint32_t>{1, 2, 3});
}

TEST_CASE("schedulability: an empty set is schedulable", "[schedulability]") {
  for (auto policy : {kFp, kEdf}) {
    const auto result = analyse({}, policy);
    CHECK(result.schedulable);
    CHECK(result.utilization == 0.0);
    CHECK(result.tasks.empty());
    CHECK(result.reason.empty());
  }
  CHECK(utilization({}) == 0.0);
}

TEST_CASE("schedulability: execution longer than the deadline fails under both policies",
          "[schedulability]") {
  const std::vector<Task> tasks{task("a", 10, 4, 3)};
  const auto fp = analyse(tasks, kFp);
  CHECK(fp.reason ==
        "task a: worst-case response at least 4ms exceeds its deadline 3ms (utilization 0.40)");
  CHECK(analyse(tasks, kEdf).reason == "task a: by its deadline at 3ms after a synchronous "
                                       "release, 4ms of work is due, more than the 3ms available "
                                       "(utilization 0.40)");
}

TEST_CASE("schedulability: long periods in nanoseconds do not overflow", "[schedulability]") {
  // Hours in nanoseconds: a (1h, 30min) above b (2h, 1h): U = 1.
  // b: R = 1h -> 1h + 30min = 1.5h -> 1h + 2*30min = 2h -> 2h.
  const std::vector<Task> tasks{Task{"a", 1h, 30min, 1h, {}}, Task{"b", 2h, 1h, 2h, {}}};
  const auto fp = analyse(tasks, kFp);
  CHECK(fp.schedulable);
  CHECK(fp.tasks[1].response_time == 2h);
  CHECK(analyse(tasks, kEdf).schedulable);

  // Near the top of the range, with coprime periods so that U = 0.6 + 0.6 cannot be summed
  // exactly in 64 bits: the analyses run and their sums saturate instead of wrapping into a
  // false pass.
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();
  constexpr std::int64_t kC = kMax / 10 * 6;
  const std::vector<Task> huge{Task{"a", Nanos{kMax - 1}, Nanos{kC}, Nanos{kMax}, {}},
                               Task{"b", Nanos{kMax}, Nanos{kC}, Nanos{kMax}, {}}};
  const auto fp_huge = analyse(huge, kFp);
  CHECK_FALSE(fp_huge.schedulable);
  CHECK(fp_huge.reason ==
        "task b: response time exceeds the 64-bit nanosecond range of the analysis");
  CHECK(meets(fp_huge) == std::vector<bool>{true, false});
  const auto edf_huge = analyse(huge, kEdf);
  CHECK_FALSE(edf_huge.schedulable);
  CHECK(edf_huge.reason == "the busy period exceeds the 64-bit nanosecond range of the analysis");
}

TEST_CASE("schedulability: an analysis too long for its budget is not schedulable",
          "[schedulability]") {
  // U = 1/2 + 499999999/1e9 < 1, so EDF needs the demand criterion for a's constrained
  // deadline: the busy period is about 1e9 ns long with a deadline of a every 2 ns, far more
  // checkpoints than the budget.
  const std::vector<Task> tasks{Task{"a", 2ns, 1ns, 1ns, {}},
                                Task{"b", 1'000'000'000ns, 499'999'999ns, 999'999'999ns, {}}};
  const auto result = analyse(tasks, kEdf);
  CHECK_FALSE(result.schedulable);
  CHECK(result.reason.find("analysis exceeded its budget") != std::string::npos);
  CHECK(meets(result) == std::vector<bool>{false, false});
}

TEST_CASE("schedulability: scheduling policy names", "[schedulability]") {
  CHECK(parse_policy("fp") == kFp);
  CHECK(parse_policy("FP") == kFp);
  CHECK(parse_policy("Fixed-Priority") == kFp);
  CHECK(parse_policy("edf") == kEdf);
  CHECK(parse_policy("EDF") == kEdf);
  CHECK_FALSE(parse_policy("rm").has_value());
  CHECK_FALSE(parse_policy("").has_value());
  CHECK_FALSE(parse_policy("edf ").has_value());
  for (auto policy : {kFp, kEdf})
    CHECK(parse_policy(to_string(policy)) == policy);
}

// ---- randomized cross-check against a discrete-time simulation ----------------------------------

namespace {

struct SimTask {
  std::int64_t period;
  std::int64_t execution;
  std::int64_t deadline;
  std::uint32_t priority; // fixed priority only
};

struct Job {
  std::size_t task;
  std::int64_t release;
  std::int64_t deadline;
  std::int64_t remaining;
};

// Whether any job misses its deadline when every task releases at 0 and then periodically,
// over [0, end). All parameters are integers, so deciding once per time unit is exact.
// Fixed priority breaks ties by input order; both break remaining ties by release.
bool simulation_misses(const std::vector<SimTask> &tasks, SchedulingPolicy policy,
                       std::int64_t end) {
  std::vector<Job> pending;
  for (std::int64_t now = 0; now < end; ++now) {
    for (std::size_t i = 0; i < tasks.size(); ++i)
      if (now % tasks[i].period == 0)
        pending.push_back({i, now, now + tasks[i].deadline, tasks[i].execution});
    for (const auto &job : pending)
      if (job.deadline <= now)
        return true;
    if (pending.empty())
      continue;
    auto before = [&](const Job &x, const Job &y) {
      if (policy == SchedulingPolicy::Edf) {
        if (x.deadline != y.deadline)
          return x.deadline < y.deadline;
      } else if (tasks[x.task].priority != tasks[y.task].priority) {
        return tasks[x.task].priority > tasks[y.task].priority;
      }
      return x.task != y.task ? x.task < y.task : x.release < y.release;
    };
    auto running = std::min_element(pending.begin(), pending.end(), before);
    if (--running->remaining == 0)
      pending.erase(running);
  }
  return false;
}

} // namespace

TEST_CASE("schedulability: analyses agree with a simulation of random task sets",
          "[schedulability][random]") {
  // Divisors of 120, so every hyperperiod is at most 120 time units.
  constexpr std::int64_t kPeriods[] = {1, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20};
  constexpr std::int64_t kHyper = 120;
  std::mt19937 rng(20240611);
  auto uniform = [&](std::int64_t lo, std::int64_t hi) {
    return std::uniform_int_distribution<std::int64_t>(lo, hi)(rng);
  };

  int fp_schedulable = 0;
  int edf_schedulable = 0;
  int edf_only = 0;
  for (int round = 0; round < 3000; ++round) {
    const auto n = static_cast<std::size_t>(uniform(1, 5));
    const bool arbitrary_deadlines = uniform(0, 1) == 0; // D up to 3T: busy periods of many jobs
    const bool explicit_priorities = uniform(0, 3) == 0;
    std::vector<Task> tasks;
    std::int64_t hyperperiod = 1;
    std::int64_t max_deadline = 0;
    std::int64_t load = 0; // U * 120, exactly
    for (std::size_t i = 0; i < n; ++i) {
      const std::int64_t t = kPeriods[uniform(0, std::size(kPeriods) - 1)];
      // Around full load in total, so that both outcomes are common.
      const std::int64_t c = uniform(1, std::max<std::int64_t>(1, 2 * t / static_cast<int>(n)));
      const std::int64_t d = arbitrary_deadlines ? uniform(1, 3 * t) : uniform(std::min(c, t), t);
      std::optional<std::uint32_t> priority;
      if (explicit_priorities && uniform(0, 4) != 0)
        priority = static_cast<std::uint32_t>(uniform(1, 4)); // ties happen
      tasks.push_back(Task{"t" + std::to_string(i), Nanos{t}, Nanos{c}, Nanos{d}, priority});
      hyperperiod = std::lcm(hyperperiod, t);
      max_deadline = std::max(max_deadline, d);
      load += c * (kHyper / t);
    }
    const bool constrained = std::all_of(tasks.begin(), tasks.end(),
                                         [](const Task &x) { return x.deadline <= x.period; });
    const std::int64_t end = hyperperiod + max_deadline;

    const auto fp = analyse(tasks, SchedulingPolicy::FixedPriority);
    const auto edf = analyse(tasks, SchedulingPolicy::Edf);
    std::vector<SimTask> sim;
    for (std::size_t i = 0; i < n; ++i)
      sim.push_back({tasks[i].period.count(), tasks[i].execution.count(), tasks[i].deadline.count(),
                     fp.tasks[i].priority});
    const bool fp_misses = simulation_misses(sim, SchedulingPolicy::FixedPriority, end);
    const bool edf_misses = simulation_misses(sim, SchedulingPolicy::Edf, end);

    std::string described = "round " + std::to_string(round) + ":";
    for (const auto &x : tasks)
      described += " (T=" + std::to_string(x.period.count()) +
                   " C=" + std::to_string(x.execution.count()) +
                   " D=" + std::to_string(x.deadline.count()) +
                   " P=" + (x.priority ? std::to_string(*x.priority) : std::string{"-"}) + ")";
    INFO(described);
    INFO("fp: " << fp.reason);
    INFO("edf: " << edf.reason);

    // (a) Response-time analysis is safe: what it accepts never misses in the simulation.
    if (fp.schedulable)
      REQUIRE_FALSE(fp_misses);
    // With distinct priorities the synchronous release is the critical instant, so it is exact
    // too (U > 1 with D > T may miss only after the simulated window).
    std::vector<std::uint32_t> used = priorities(fp);
    std::sort(used.begin(), used.end());
    const bool distinct = std::adjacent_find(used.begin(), used.end()) == used.end();
    if (distinct && (constrained || load <= kHyper))
      REQUIRE(fp.schedulable == !fp_misses);
    // (b) The EDF analysis is exact for synchronous periodic tasks.
    if (constrained || load <= kHyper)
      REQUIRE(edf.schedulable == !edf_misses);
    // (c) EDF is optimal on one processor.
    if (fp.schedulable)
      REQUIRE(edf.schedulable);

    fp_schedulable += fp.schedulable ? 1 : 0;
    edf_schedulable += edf.schedulable ? 1 : 0;
    edf_only += edf.schedulable && !fp.schedulable ? 1 : 0;
  }
  // The generator must exercise both outcomes, and the gap between the policies.
  CHECK(fp_schedulable > 300);
  CHECK(edf_schedulable - fp_schedulable > 30);
  CHECK(3000 - edf_schedulable > 300);
  CHECK(edf_only == edf_schedulable - fp_schedulable);
}
