// How the ends of a data connection count the QoS problems DDS would count for them: the
// deadline and lost liveliness of in-host and same-host connections, which have no DDS entity to
// do it (component/data_connection.hpp), and DDS's own counts for the others.
#include <chrono>

#include "component/data_connection.hpp"

namespace rsca::component {
namespace detail {
namespace {

// Whole deadline periods from `since_ns` to `now_ns`.
std::uint32_t periods_between(std::int64_t since_ns, std::int64_t now_ns,
                              std::chrono::nanoseconds deadline) {
  if (since_ns == 0 || deadline.count() <= 0 || now_ns <= since_ns)
    return 0;
  return static_cast<std::uint32_t>((now_ns - since_ns) / deadline.count());
}

// An in-host reader's requested deadline, counted as DDS counts it (once a sample has arrived,
// each period without one): the periods of the current gap not reported yet.
std::uint32_t local_deadline_misses(DataConnection &c) {
  // A sample since the last look began a new gap (one a TCP stream's thread delivered too).
  const std::int64_t last = c.last_sample_ns.load(std::memory_order_relaxed);
  if (last != c.deadline_gap_ns) {
    c.deadline_gap_ns = last;
    c.deadline_periods_reported = 0;
  }
  const auto periods = periods_between(last, steady_ns(), c.deadline);
  if (periods <= c.deadline_periods_reported)
    return 0;
  const std::uint32_t missed = periods - c.deadline_periods_reported;
  c.deadline_periods_reported = periods;
  c.deadline_missed.fetch_add(missed, std::memory_order_relaxed);
  return missed;
}

// A same-host reader's lost liveliness not reported yet: writers whose process ended while
// connected (the node counts them in the ring, and so does its relay for writers on other hosts
// that DDS saw lose theirs), or a lease that passed since a writer was last alive. Once per gap,
// as DDS counts a writer going from alive to not alive: a gap is the ring's last sign of life,
// reported once whichever way it was seen.
std::uint32_t lost_writers(DataConnection &c) {
  if (!c.ring_reader)
    return 0;
  const std::uint32_t lost = c.ring_reader->writers_lost();
  const std::uint32_t change = lost - c.writers_lost_reported;
  c.writers_lost_reported = lost;
  const std::int64_t alive = c.ring_reader->alive_ns();
  if (change > 0) {
    c.lost_at_alive_ns = alive;
    return change;
  }
  if (c.lease.count() <= 0 || alive == 0 || alive == c.lost_at_alive_ns)
    return 0;
  // A writer on another host is alive while its node's relay says so (DDS liveliness).
  const bool expired = steady_ns() - alive > c.lease.count() && c.ring_reader->remote_alive() == 0;
  if (!expired)
    return 0;
  c.lost_at_alive_ns = alive;
  return 1;
}

} // namespace

std::int64_t steady_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// An in-host writer's offered deadline: the periods each gap between writes spanned.
void note_local_write(DataConnection &c) {
  if (c.deadline.count() <= 0)
    return;
  const std::int64_t now = steady_ns();
  const std::int64_t before = c.last_sample_ns.exchange(now, std::memory_order_relaxed);
  if (auto missed = periods_between(before, now, c.deadline); missed > 0)
    c.deadline_missed.fetch_add(missed, std::memory_order_relaxed);
}

void note_held_arrivals(DataConnection &c) {
  const std::uint64_t arrivals = c.ring_reader ? c.ring_reader->written()
                                 : c.inbox     ? c.inbox->pushed()
                                               : 0;
  if (arrivals == c.held_arrivals)
    return;
  c.held_arrivals = arrivals;
  c.last_sample_ns.store(steady_ns(), std::memory_order_relaxed);
}

// How often the writer (uses) or the reader's writers (provides) missed the connection's deadline.
std::uint32_t deadline_misses(const DataConnection &c, profile::PortDirection direction) {
  if (c.own_deadline() && direction == profile::PortDirection::Uses) // and the current gap
    return c.deadline_missed.load(std::memory_order_relaxed) +
           periods_between(c.last_sample_ns.load(std::memory_order_relaxed), steady_ns(),
                           c.deadline);
  if (c.own_deadline())
    return c.deadline_missed.load(std::memory_order_relaxed);
  const dds_entity_t entity = c.entity.get();
  if (direction == profile::PortDirection::Uses) {
    dds_offered_deadline_missed_status_t status{};
    return dds_get_offered_deadline_missed_status(entity, &status) == 0 ? status.total_count : 0;
  }
  dds_requested_deadline_missed_status_t status{};
  return dds_get_requested_deadline_missed_status(entity, &status) == 0 ? status.total_count : 0;
}

} // namespace detail

using detail::DataConnection;
using detail::local_deadline_misses;
using detail::lost_writers;

std::vector<ConnectionProblem> PortBase::take_problems() {
  std::vector<ConnectionProblem> out;
  if (direction_ != profile::PortDirection::Provides)
    return out;
  std::shared_lock lock(mutex_);
  constexpr std::uint32_t kProblems =
      DDS_REQUESTED_DEADLINE_MISSED_STATUS | DDS_LIVELINESS_CHANGED_STATUS;
  for (const auto &[id, c] : connections_) {
    if (c->own_deadline()) {
      if (auto missed = local_deadline_misses(*c); missed > 0)
        out.push_back({id, "deadline missed", missed});
      if (auto lost = lost_writers(*c); lost > 0)
        out.push_back({id, "liveliness lost", lost});
      continue;
    }
    std::uint32_t changed = 0;
    if (dds_get_status_changes(c->entity.get(), &changed) != 0 || (changed & kProblems) == 0)
      continue;
    dds_requested_deadline_missed_status_t deadline{};
    if (dds_get_requested_deadline_missed_status(c->entity.get(), &deadline) == 0 &&
        deadline.total_count_change > 0)
      out.push_back(
          {id, "deadline missed", static_cast<std::uint32_t>(deadline.total_count_change)});
    dds_liveliness_changed_status_t liveliness{};
    if (dds_get_liveliness_changed_status(c->entity.get(), &liveliness) == 0 &&
        liveliness.not_alive_count_change > 0)
      out.push_back(
          {id, "liveliness lost", static_cast<std::uint32_t>(liveliness.not_alive_count_change)});
  }
  return out;
}

} // namespace rsca::component
