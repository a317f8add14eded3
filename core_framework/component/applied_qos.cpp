// What one end of a connection applies of its QoS (component/ports.hpp AppliedQos), read back
// from its live transport rather than copied from what the domain asked for: a QoS check that
// reads these fails when an end drops a policy on the way.
#include <memory>

#include "component/data_connection.hpp"

namespace rsca::component::detail {
namespace {

using profile::Durability;
using profile::History;
using profile::Liveliness;
using profile::Ownership;
using profile::Reliability;

std::int64_t finite_ns(dds_duration_t d) {
  return d == DDS_INFINITY ? 0 : static_cast<std::int64_t>(d);
}

Durability durability_of(dds_durability_kind_t kind) {
  switch (kind) {
  case DDS_DURABILITY_TRANSIENT_LOCAL:
    return Durability::TransientLocal;
  case DDS_DURABILITY_TRANSIENT:
    return Durability::Transient;
  case DDS_DURABILITY_PERSISTENT:
    return Durability::Persistent;
  default:
    return Durability::Volatile;
  }
}

Liveliness liveliness_of(dds_liveliness_kind_t kind) {
  switch (kind) {
  case DDS_LIVELINESS_MANUAL_BY_PARTICIPANT:
    return Liveliness::ManualByParticipant;
  case DDS_LIVELINESS_MANUAL_BY_TOPIC:
    return Liveliness::ManualByTopic;
  default:
    return Liveliness::Automatic;
  }
}

// The QoS Cyclone holds for the reader or writer itself.
std::optional<AppliedQos> dds_entity_qos(dds_entity_t entity) {
  const std::unique_ptr<dds_qos_t, decltype(&dds_delete_qos)> qos(dds_create_qos(),
                                                                  &dds_delete_qos);
  if (dds_get_qos(entity, qos.get()) < 0)
    return std::nullopt;
  AppliedQos a;
  dds_reliability_kind_t reliability = DDS_RELIABILITY_BEST_EFFORT;
  dds_duration_t blocking = 0;
  dds_history_kind_t history = DDS_HISTORY_KEEP_LAST;
  std::int32_t depth = 1;
  dds_durability_kind_t durability = DDS_DURABILITY_VOLATILE;
  dds_ownership_kind_t ownership = DDS_OWNERSHIP_SHARED;
  dds_duration_t deadline = DDS_INFINITY;
  dds_liveliness_kind_t liveliness = DDS_LIVELINESS_AUTOMATIC;
  dds_duration_t lease = DDS_INFINITY;
  if (!dds_qget_reliability(qos.get(), &reliability, &blocking) ||
      !dds_qget_history(qos.get(), &history, &depth) ||
      !dds_qget_durability(qos.get(), &durability) || !dds_qget_ownership(qos.get(), &ownership) ||
      !dds_qget_deadline(qos.get(), &deadline) ||
      !dds_qget_liveliness(qos.get(), &liveliness, &lease))
    return std::nullopt;
  a.reliability =
      reliability == DDS_RELIABILITY_RELIABLE ? Reliability::Reliable : Reliability::BestEffort;
  a.history = history == DDS_HISTORY_KEEP_ALL ? History::KeepAll : History::KeepLast;
  a.depth = history == DDS_HISTORY_KEEP_ALL ? 0 : depth;
  a.durability = durability_of(durability);
  a.ownership = ownership == DDS_OWNERSHIP_EXCLUSIVE ? Ownership::Exclusive : Ownership::Shared;
  a.deadline_ns = finite_ns(deadline);
  a.liveliness = liveliness_of(liveliness);
  a.lease_ns = finite_ns(lease);
  return a;
}

// A reader's queue of `depth` (0: all) as a history.
void keep(AppliedQos &a, std::size_t depth) {
  a.history = depth == 0 ? History::KeepAll : History::KeepLast;
  a.depth = static_cast<std::int32_t>(depth);
}

} // namespace

std::optional<AppliedQos> applied_qos(const DataConnection &c) {
  if (!c.own_deadline())
    return c.entity ? dds_entity_qos(c.entity.get()) : std::nullopt;
  // A ring, a TCP stream and an in-host topic deliver in order and lose nothing while a reader
  // keeps up (a stream breaks rather than drop); each delivers every writer (shared).
  AppliedQos a;
  a.deadline_ns = c.deadline.count();
  if (c.ring_writer) {
    // The ring keeps its last records for a late joiner, whatever the writer asked.
    keep(a, c.ring_writer->records());
    a.durability = Durability::TransientLocal;
  } else if (c.ring_reader) {
    keep(a, c.ring_reader->depth());
    a.durability = c.durable ? Durability::TransientLocal : Durability::Volatile;
  } else if (c.inbox) {
    keep(a, c.inbox->depth()); // a TCP stream's or an in-host reader's queue
  } else {
    keep(a, 0); // a TCP or in-host writer hands every sample on
  }
  if (c.same_host()) { // only a ring checks (reader) or asserts (writer) a liveliness lease
    a.liveliness = c.liveliness;
    a.lease_ns = c.lease.count();
  }
  return a;
}

} // namespace rsca::component::detail
