#include "allocator/schedulability.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <compare>
#include <limits>
#include <numeric>
#include <tuple>
#include <utility>

#include <fmt/format.h>

#include "common/units.hpp"

namespace rsca::allocator {
namespace {

using Rep = Nanos::rep;
constexpr Rep kMaxRep = std::numeric_limits<Rep>::max();
constexpr std::uint64_t kMaxU64 = std::numeric_limits<std::uint64_t>::max();

// Non-negative nanosecond arithmetic that saturates instead of wrapping: a wrapped sum could
// look like a response inside the deadline. Callers treat kMaxRep as "out of range".
Rep add(Rep a, Rep b) {
  return a > kMaxRep - b ? kMaxRep : a + b;
}

Rep multiply(Rep a, Rep b) {
  return b != 0 && a > kMaxRep / b ? kMaxRep : a * b;
}

Rep ceil_div(Rep a, Rep b) {
  return a / b + (a % b != 0 ? 1 : 0);
}

std::string text(Rep ns) {
  return format_duration(Duration{Nanos{ns}});
}

// Two decimals, or more when two would round an overload down to "1.00" or a set just under
// full load up to it: the reason must not contradict itself.
std::string format_utilization(double u) {
  for (int decimals = 2; decimals < 9; ++decimals) {
    const double scale = std::pow(10.0, decimals);
    if (u == 1.0 || std::round(u * scale) != scale)
      return fmt::format("{:.{}f}", u, decimals);
  }
  return fmt::format("{:.9f}", u);
}

// Steps left before the analysis gives up; bounds the time an admission can take.
class Budget {
public:
  bool spend() {
    if (left_ == 0)
      return false;
    --left_;
    return true;
  }

private:
  std::size_t left_ = kAnalysisBudget;
};

enum class Outcome : std::uint8_t { Ok, Missed, Overflow, OutOfBudget };

std::optional<std::string> invalid_reason(const Task &task) {
  auto positive = [&](const char *what, Nanos value) -> std::optional<std::string> {
    if (value > Nanos::zero())
      return std::nullopt;
    return fmt::format("task {}: {} must be positive, got {}", task.id, what, text(value.count()));
  };
  if (auto reason = positive("period", task.period))
    return reason;
  if (auto reason = positive("execution time", task.execution))
    return reason;
  return positive("deadline", task.deadline);
}

std::optional<std::string> first_invalid(const std::vector<Task> &tasks) {
  for (const auto &task : tasks)
    if (auto reason = invalid_reason(task))
      return reason;
  return std::nullopt;
}

// How sum C/T compares with 1, in exact rational arithmetic: floating point misjudges sets at
// exactly full load (1/2 + 1/3 + 1/6). Nullopt when the common denominator outgrows 64 bits;
// callers then fall back to an analysis that does not need it.
std::optional<std::strong_ordering> compare_load_to_one(const std::vector<Task> &tasks) {
  std::uint64_t num = 0;
  std::uint64_t den = 1;
  for (const auto &task : tasks) {
    const auto c = static_cast<std::uint64_t>(task.execution.count());
    const auto t = static_cast<std::uint64_t>(task.period.count());
    if (c > t) // this task alone overloads the processor
      return std::strong_ordering::greater;
    const std::uint64_t g = std::gcd(den, t);
    const std::uint64_t sum_scale = t / g; // the new denominator is den * (t / g) = t * (den / g)
    const std::uint64_t task_scale = den / g;
    if (den > kMaxU64 / sum_scale || num > kMaxU64 / sum_scale || c > kMaxU64 / task_scale)
      return std::nullopt;
    const std::uint64_t scaled_num = num * sum_scale;
    const std::uint64_t scaled_c = c * task_scale;
    if (scaled_num > kMaxU64 - scaled_c)
      return std::nullopt;
    den *= sum_scale;
    num = scaled_num + scaled_c;
    if (num > den) // terms are positive: it cannot come back under 1
      return std::strong_ordering::greater;
    const std::uint64_t r = std::gcd(num, den);
    num /= r;
    den /= r;
  }
  return num <=> den;
}

bool overloaded(const std::vector<Task> &tasks) {
  return compare_load_to_one(tasks) == std::strong_ordering::greater;
}

// Explicit priorities are kept; the others get deadline-monotonic priorities below all of them
// (see the header for why and for the saturation at 0).
std::vector<std::uint32_t> assign_priorities(const std::vector<Task> &tasks) {
  std::vector<std::uint32_t> priorities(tasks.size(), 0);
  std::vector<std::size_t> unprioritised;
  std::optional<std::uint32_t> lowest_explicit;
  for (std::size_t i = 0; i < tasks.size(); ++i) {
    if (!tasks[i].priority) {
      unprioritised.push_back(i);
      continue;
    }
    priorities[i] = *tasks[i].priority;
    lowest_explicit = std::min(lowest_explicit.value_or(priorities[i]), priorities[i]);
  }
  std::stable_sort(unprioritised.begin(), unprioritised.end(), [&](std::size_t a, std::size_t b) {
    return std::tie(tasks[a].deadline, tasks[a].period) <
           std::tie(tasks[b].deadline, tasks[b].period);
  });
  constexpr std::uint64_t kMaxPriority = std::numeric_limits<std::uint32_t>::max();
  std::uint64_t above = lowest_explicit
                            ? *lowest_explicit
                            : std::min<std::uint64_t>(unprioritised.size() + 1, kMaxPriority);
  for (std::size_t i : unprioritised) {
    above = above > 0 ? above - 1 : 0;
    priorities[i] = static_cast<std::uint32_t>(above);
  }
  return priorities;
}

// Every other task at the same or a higher priority: ties interfere both ways because the
// dispatcher's order among equals is not known.
std::vector<std::size_t> interferers(const std::vector<TaskVerdict> &verdicts, std::size_t i) {
  std::vector<std::size_t> result;
  for (std::size_t j = 0; j < verdicts.size(); ++j)
    if (j != i && verdicts[j].priority >= verdicts[i].priority)
      result.push_back(j);
  return result;
}

Rep interference(const std::vector<Task> &tasks, const std::vector<std::size_t> &from, Rep window) {
  Rep total = 0;
  for (std::size_t j : from)
    total =
        add(total, multiply(ceil_div(window, tasks[j].period.count()), tasks[j].execution.count()));
  return total;
}

struct Response {
  Outcome outcome = Outcome::Ok;
  Rep time = 0; // worst response (Ok), or the first iterate past the deadline (Missed)
  Rep job = 0;  // the job of the busy period it belongs to, from 0
};

// Response-time analysis of one task. Job q of the level-i busy period completes at the least
// fixed point of w = (q+1)C + I(w); iterates from below are lower bounds of it, so the first one
// past the deadline proves the miss. With D <= T the busy period holds one job unless that job
// already misses, and this is Joseph & Pandya's recurrence; with D > T it is Lehoczky's.
Response response_time(const std::vector<Task> &tasks, const std::vector<std::size_t> &higher,
                       std::size_t i, Budget &budget) {
  const Rep c = tasks[i].execution.count();
  const Rep t = tasks[i].period.count();
  const Rep d = tasks[i].deadline.count();
  Rep worst = 0;
  Rep window = c;
  for (Rep job = 0;; ++job) {
    // The window only ever exceeded job * t to get here, so this product does not saturate.
    const Rep release = multiply(job, t);
    const Rep own = multiply(job + 1, c);
    for (;;) {
      if (!budget.spend())
        return {Outcome::OutOfBudget};
      const Rep next = add(own, interference(tasks, higher, window));
      if (next == kMaxRep)
        return {Outcome::Overflow};
      if (next - release > d)
        return {Outcome::Missed, next - release, job};
      if (next == window)
        break;
      window = next;
    }
    worst = std::max(worst, window - release);
    if (window <= add(release, t)) // the busy period ends before the next job is released
      return {Outcome::Ok, worst, job};
    // Job q+1 finishes at least one execution after job q: a valid start from below.
    window = add(window, c);
  }
}

Schedulability start(const std::vector<Task> &tasks, const std::vector<std::uint32_t> &priorities) {
  Schedulability result;
  result.utilization = utilization(tasks);
  result.tasks.reserve(tasks.size());
  for (std::size_t i = 0; i < tasks.size(); ++i)
    result.tasks.push_back({tasks[i].id, priorities[i], Nanos::zero(), false});
  return result;
}

// Marks the set not schedulable; the first reason given is the one kept.
void reject(Schedulability &result, std::string reason) {
  result.schedulable = false;
  if (result.reason.empty())
    result.reason = std::move(reason);
}

std::string overload_reason(const Schedulability &result) {
  return fmt::format("utilization {} exceeds 1: the processor cannot keep up",
                     format_utilization(result.utilization));
}

std::string budget_reason(std::string_view prefix, const Schedulability &result) {
  return fmt::format("{}analysis exceeded its budget of {} steps (utilization {}); treated as "
                     "not schedulable",
                     prefix, kAnalysisBudget, format_utilization(result.utilization));
}

std::string miss_reason(const Task &task, const Response &response, const Schedulability &result) {
  const std::string job = response.job == 0
                              ? std::string{}
                              : fmt::format("job {} of a busy period; ", response.job + 1);
  return fmt::format("task {}: worst-case response at least {} exceeds its deadline {} ({}"
                     "utilization {})",
                     task.id, text(response.time), text(task.deadline.count()), job,
                     format_utilization(result.utilization));
}

Schedulability analyse_fixed_priority(const std::vector<Task> &tasks, Schedulability result) {
  if (overloaded(tasks)) {
    reject(result, overload_reason(result));
    return result;
  }
  Budget budget;
  for (std::size_t i = 0; i < tasks.size(); ++i) {
    const Response response = response_time(tasks, interferers(result.tasks, i), i, budget);
    auto &verdict = result.tasks[i];
    const std::string prefix = fmt::format("task {}: ", tasks[i].id);
    switch (response.outcome) {
    case Outcome::Ok:
      verdict.response_time = Nanos{response.time};
      verdict.meets_deadline = true;
      break;
    case Outcome::Missed:
      verdict.response_time = Nanos{response.time};
      reject(result, miss_reason(tasks[i], response, result));
      break;
    case Outcome::Overflow:
      reject(result, prefix + "response time exceeds the 64-bit nanosecond range of the analysis");
      break;
    case Outcome::OutOfBudget:
      reject(result, budget_reason(prefix, result));
      return result;
    }
  }
  return result;
}

struct Bound {
  Outcome outcome = Outcome::Ok;
  Rep value = 0;
};

// The synchronous busy period: least fixed point of w = sum ceil(w/T) C, iterated from sum C.
// A deadline miss under EDF, if any, happens at a deadline inside it.
Bound busy_period(const std::vector<Task> &tasks, Budget &budget) {
  Rep window = 0;
  for (const auto &task : tasks)
    window = add(window, task.execution.count());
  for (;;) {
    if (!budget.spend())
      return {Outcome::OutOfBudget};
    Rep next = 0;
    for (const auto &task : tasks)
      next = add(next, multiply(ceil_div(window, task.period.count()), task.execution.count()));
    if (next == kMaxRep)
      return {Outcome::Overflow};
    if (next == window)
      return {Outcome::Ok, window};
    window = next;
  }
}

struct Demand {
  Outcome outcome = Outcome::Ok;
  std::size_t task = 0; // the first task (input order) with a deadline at `time`
  Rep time = 0;
  Rep demand = 0;
};

// The processor-demand criterion h(t) <= t at every absolute deadline t up to `horizon`, in
// increasing order so that a failure names the earliest deadline that cannot be met. h only
// grows at deadlines, so it is accumulated job by job instead of recomputed.
Demand check_demand(const std::vector<Task> &tasks, Rep horizon, Budget &budget) {
  std::vector<Rep> next_deadline;
  next_deadline.reserve(tasks.size());
  for (const auto &task : tasks)
    next_deadline.push_back(task.deadline.count());
  Rep demand = 0;
  while (!next_deadline.empty()) {
    const Rep t = *std::min_element(next_deadline.begin(), next_deadline.end());
    if (t > horizon)
      break;
    std::optional<std::size_t> due;
    for (std::size_t i = 0; i < tasks.size(); ++i) {
      if (next_deadline[i] != t)
        continue;
      if (!budget.spend())
        return {Outcome::OutOfBudget};
      demand = add(demand, tasks[i].execution.count());
      next_deadline[i] = add(t, tasks[i].period.count());
      due = due.value_or(i);
    }
    if (demand > t)
      return {Outcome::Missed, *due, t, demand};
  }
  return {};
}

Schedulability all_meet(const std::vector<Task> &tasks, Schedulability result) {
  for (std::size_t i = 0; i < tasks.size(); ++i) {
    result.tasks[i].response_time = tasks[i].deadline;
    result.tasks[i].meets_deadline = true;
  }
  return result;
}

Schedulability analyse_edf(const std::vector<Task> &tasks, Schedulability result) {
  const auto load = compare_load_to_one(tasks);
  if (load == std::strong_ordering::greater) {
    reject(result, overload_reason(result));
    return result;
  }
  const bool no_deadline_before_period = std::all_of(
      tasks.begin(), tasks.end(), [](const Task &task) { return task.deadline >= task.period; });
  if (load && no_deadline_before_period)
    return all_meet(tasks, std::move(result));

  Budget budget;
  const Bound horizon = busy_period(tasks, budget);
  if (horizon.outcome == Outcome::Overflow) {
    reject(result, "the busy period exceeds the 64-bit nanosecond range of the analysis");
    return result;
  }
  const Demand demand = horizon.outcome == Outcome::Ok ? check_demand(tasks, horizon.value, budget)
                                                       : Demand{Outcome::OutOfBudget};
  if (demand.outcome == Outcome::Ok)
    return all_meet(tasks, std::move(result));
  if (demand.outcome == Outcome::Missed)
    reject(result, fmt::format("task {}: by its deadline at {} after a synchronous release, {} of "
                               "work is due, more than the {} available (utilization {})",
                               tasks[demand.task].id, text(demand.time), text(demand.demand),
                               text(demand.time), format_utilization(result.utilization)));
  else
    reject(result, budget_reason("", result));
  return result;
}

} // namespace

std::string_view to_string(SchedulingPolicy policy) {
  switch (policy) {
  case SchedulingPolicy::FixedPriority:
    return "fixed-priority";
  case SchedulingPolicy::Edf:
    return "edf";
  }
  return "unknown";
}

std::optional<SchedulingPolicy> parse_policy(std::string_view text) {
  std::string lower(text);
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  if (lower == "fp" || lower == "fixed-priority")
    return SchedulingPolicy::FixedPriority;
  if (lower == "edf")
    return SchedulingPolicy::Edf;
  return std::nullopt;
}

Schedulability analyse(const std::vector<Task> &tasks, SchedulingPolicy policy) {
  const bool fixed_priority = policy == SchedulingPolicy::FixedPriority;
  auto result = start(tasks, fixed_priority ? assign_priorities(tasks)
                                            : std::vector<std::uint32_t>(tasks.size(), 0));
  if (auto reason = first_invalid(tasks)) {
    reject(result, std::move(*reason));
    return result;
  }
  return fixed_priority ? analyse_fixed_priority(tasks, std::move(result))
                        : analyse_edf(tasks, std::move(result));
}

double utilization(const std::vector<Task> &tasks) {
  double total = 0.0;
  for (const auto &task : tasks)
    if (task.period > Nanos::zero() && task.execution > Nanos::zero())
      total +=
          static_cast<double>(task.execution.count()) / static_cast<double>(task.period.count());
  return total;
}

double liu_layland_bound(std::size_t n) {
  if (n == 0)
    return 1.0;
  const auto count = static_cast<double>(n);
  return count * (std::pow(2.0, 1.0 / count) - 1.0);
}

} // namespace rsca::allocator
