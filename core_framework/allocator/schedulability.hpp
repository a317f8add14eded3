// Real-time schedulability of periodic tasks on one preemptive processor: whether every job
// meets its deadline under fixed priorities (response-time analysis) or EDF (processor demand).
// The ResourceAllocator's timing admission uses it; it knows nothing of profiles or DDS.
//
// Every task is periodic (or sporadic with minimum inter-arrival `period`), independent (no
// blocking, no self-suspension), with zero release jitter and zero context-switch cost. The
// analysis is exact under those assumptions except where noted, and always errs towards
// "not schedulable": an admission must never accept a set that can miss a deadline.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rsca::allocator {

using Nanos = std::chrono::nanoseconds;

struct Task {
  std::string id;
  Nanos period;    // T > 0
  Nanos execution; // C > 0: worst-case execution time per period
  Nanos deadline;  // D > 0, relative to release; callers pass the period when none is given.
                   // D > T is allowed (several jobs of a task may then be pending at once).
  // Fixed priority, larger = more urgent; none = deadline monotonic. Ignored by EDF.
  std::optional<std::uint32_t> priority;

  friend bool operator==(const Task &, const Task &) = default;
};

enum class SchedulingPolicy : std::uint8_t { FixedPriority, Edf };
std::string_view to_string(SchedulingPolicy policy); // "fixed-priority", "edf"
// "fp", "fixed-priority" or "edf", in any case.
std::optional<SchedulingPolicy> parse_policy(std::string_view text);

struct TaskVerdict {
  std::string id;
  // Fixed priority: the priority analysed (given, or assigned as described at analyse()).
  // EDF: 0.
  std::uint32_t priority = 0;
  // Fixed priority: the worst-case response time when the deadline is met; when it is missed,
  // the value at which the analysis stopped, past the deadline (a lower bound of the true one).
  // EDF: the deadline when the set is schedulable.
  // Zero when the task was not analysed (invalid set, utilization above 1, budget exhausted,
  // or an EDF set that fails, where no task's deadline is guaranteed).
  Nanos response_time{0};
  bool meets_deadline = false;
};

struct Schedulability {
  bool schedulable = true;
  double utilization = 0.0;       // sum C/T
  std::vector<TaskVerdict> tasks; // in input order
  // Empty when schedulable; otherwise one sentence naming the first failing task (input order)
  // and the numbers, e.g. "task b: worst-case response at least 14ms exceeds its deadline
  // 12ms (utilization 0.93)".
  std::string reason;
};

// The most steps (response-time recurrence steps, busy-period steps and EDF deadline
// checkpoints together) one analyse() call takes; past it the set is reported not schedulable
// ("analysis exceeded its budget"), which is conservative.
inline constexpr std::size_t kAnalysisBudget = 1'000'000;

// Fixed priority: response-time analysis (Joseph & Pandya, Audsley; Lehoczky's busy-period
// extension when D > T), in integer nanoseconds. Tasks sharing a priority are each analysed as
// if the others preempted them (conservative: the dispatcher's tie order is unknown).
// Priority assignment: tasks with an explicit priority keep it. Tasks without one are ordered
// deadline monotonic among themselves (shorter D first, then shorter T, then input order) and
// ranked below every explicitly prioritised task: they count down from one below the lowest
// explicit priority (from their number when no task has one, so the least urgent gets 1). When
// the numbers run out they saturate at 0 and share it; the analysis uses the numbers reported,
// so that is pessimistic but still safe to deploy as is.
// Utilization above 1 fails without per-task analysis.
//
// EDF (preemptive, uniprocessor): with every D >= T, schedulable iff utilization <= 1
// (decided in exact rational arithmetic). Otherwise the processor-demand criterion
// h(t) <= t at every absolute deadline t within the synchronous busy period.
//
// An empty set is schedulable. A task with a non-positive period, execution or deadline makes
// the set not schedulable, with a reason naming it. Never throws for bad input.
Schedulability analyse(const std::vector<Task> &tasks, SchedulingPolicy policy);

// Sum of C/T; tasks with a non-positive period or execution contribute nothing.
double utilization(const std::vector<Task> &tasks);

// Liu & Layland's rate-monotonic utilization bound n(2^(1/n) - 1) for implicit deadlines:
// a sufficient test only (1 for n = 0 and n = 1; tends to ln 2).
double liu_layland_bound(std::size_t n);

} // namespace rsca::allocator
