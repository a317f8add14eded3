#include "dds/port_qos.hpp"

#include <array>
#include <limits>

#include <fmt/format.h>

#include "common/names.hpp"
#include "profile/connection_qos.hpp"

namespace rsca::dds {
namespace {

using Json = nlohmann::json;
using profile::ConnectionQos;
using profile::Durability;
using profile::History;
using profile::Liveliness;
using profile::Ownership;
using profile::Reliability;
using profile::Transport;

constexpr const char *kInfinite = "infinite";
constexpr dds_duration_t kMaxBlockingTime = DDS_MSECS(100);

// The wire's names of the durations, in whole nanoseconds (qos_to_json), beside the SAD's.
struct NanosecondKey {
  const char *wire;
  const char *sad;
  std::optional<Duration> ConnectionQos::*field;
};
constexpr std::array<NanosecondKey, 3> kNanosecondKeys{
    {{"deadline_ns", "deadline", &ConnectionQos::deadline},
     {"latencybudget_ns", "latencybudget", &ConnectionQos::latency_budget},
     {"lease_ns", "lease", &ConnectionQos::lease}}};

tl::unexpected<Error> qos_error(std::string message) {
  return make_error({"qos", 0, 0}, "qos", std::move(message));
}

// The defaults of docs/profiles.md for every field the SAD leaves out.
ConnectionQos with_defaults(ConnectionQos qos) {
  qos.reliability = qos.reliability.value_or(Reliability::Reliable);
  qos.durability = qos.durability.value_or(Durability::Volatile);
  qos.history = qos.history.value_or(History::KeepLast);
  if (qos.history == History::KeepLast)
    qos.depth = qos.depth.value_or(kDefaultDepth);
  else
    qos.depth.reset();
  qos.deadline = qos.deadline.value_or(Duration{});
  qos.latency_budget = qos.latency_budget.value_or(Duration{std::chrono::nanoseconds(0)});
  qos.transport_priority = qos.transport_priority.value_or(0);
  qos.liveliness = qos.liveliness.value_or(Liveliness::Automatic);
  qos.lease = qos.lease.value_or(Duration{});
  qos.ownership = qos.ownership.value_or(Ownership::Shared);
  qos.strength = qos.strength.value_or(0);
  // Not named: the nodes' when they honour the rest, else direct DDS (profile/connection_qos.hpp).
  qos.transport = qos.transport.value_or(profile::transport_for(qos));
  return qos;
}

// Durations ordered with infinite as the longest.
bool longer(const Duration &a, const Duration &b) {
  if (a.infinite())
    return !b.infinite();
  return !b.infinite() && *a.value > *b.value;
}

std::string duration_text(const Duration &d) {
  return d.infinite() ? std::string(kInfinite) : format_duration(d);
}

Json duration_json(const Duration &duration) {
  if (duration.infinite())
    return kInfinite;
  return duration.value->count();
}

Expected<Duration> duration_from_json(const Json &json, const char *key) {
  if (json.is_string() && json.get_ref<const std::string &>() == kInfinite)
    return Duration{};
  if (json.is_number_integer() && json.get<std::int64_t>() >= 0 &&
      !(json.is_number_unsigned() &&
        json.get<std::uint64_t>() > std::uint64_t(std::numeric_limits<std::int64_t>::max())))
    return Duration{std::chrono::nanoseconds(json.get<std::int64_t>())};
  return qos_error(fmt::format("\"{}\" is {}, not whole nanoseconds or \"infinite\"", key,
                               excerpt(json.dump())));
}

// A SAD attribute's value as text: a string as it is, anything else as JSON writes it (rsca
// connect sends numbers as numbers).
std::string text_of(const Json &value) {
  return value.is_string() ? value.get<std::string>() : value.dump();
}

// `key`, a SAD <qos> attribute, by the SAD's own parser (profile/connection_qos.hpp).
Expected<void> read_attribute(ConnectionQos &qos, const std::string &key, const Json &value) {
  if (auto set = profile::set_qos_attribute(qos, key, text_of(value)); !set)
    return qos_error(fmt::format("\"{}\" is {}, {}", key, excerpt(value.dump()), set.error()));
  return {};
}

// `key`, a duration in whole nanoseconds (the wire's form), into the field its SAD name names.
Expected<void> read_nanoseconds(ConnectionQos &qos, const std::string &key, const Json &value,
                                const Json &json) {
  for (const auto &k : kNanosecondKeys) {
    if (key != k.wire)
      continue;
    if (json.contains(k.sad))
      return qos_error(fmt::format("give \"{}\" or \"{}\", not both", k.sad, k.wire));
    auto duration = duration_from_json(value, k.wire);
    if (!duration)
      return tl::unexpected(duration.error());
    qos.*k.field = *duration;
    return {};
  }
  return qos_error(fmt::format("unknown QoS \"{}\"", excerpt(key)));
}

// The SAD's names and values ("deadline": "100ms"), and the wire's durations in nanoseconds
// ("deadline_ns": 100000000); unknown keys are refused.
Expected<ConnectionQos> parse(const Json &json) {
  if (!json.is_object())
    return qos_error(fmt::format("the QoS is {}, not an object", excerpt(json.dump())));
  ConnectionQos qos;
  for (const auto &[key, value] : json.items()) {
    auto ok = profile::is_qos_attribute(key) ? read_attribute(qos, key, value)
                                             : read_nanoseconds(qos, key, value, json);
    if (!ok)
      return tl::unexpected(ok.error());
  }
  return with_defaults(std::move(qos));
}

dds_duration_t dds_duration(const Duration &duration) {
  return duration.infinite() ? DDS_INFINITY : duration.value->count();
}

dds_reliability_kind_t dds_kind(Reliability v) {
  return v == Reliability::Reliable ? DDS_RELIABILITY_RELIABLE : DDS_RELIABILITY_BEST_EFFORT;
}
dds_durability_kind_t dds_kind(Durability v) {
  constexpr dds_durability_kind_t kinds[] = {DDS_DURABILITY_VOLATILE,
                                             DDS_DURABILITY_TRANSIENT_LOCAL,
                                             DDS_DURABILITY_TRANSIENT, DDS_DURABILITY_PERSISTENT};
  return kinds[static_cast<std::size_t>(v)];
}
dds_liveliness_kind_t dds_kind(Liveliness v) {
  constexpr dds_liveliness_kind_t kinds[] = {DDS_LIVELINESS_AUTOMATIC,
                                             DDS_LIVELINESS_MANUAL_BY_PARTICIPANT,
                                             DDS_LIVELINESS_MANUAL_BY_TOPIC};
  return kinds[static_cast<std::size_t>(v)];
}

// `qos` has every field set (with_defaults).
Qos make_dds_qos(const ConnectionQos &qos) {
  auto out = make_qos();
  dds_qos_t *q = out.get();
  dds_qset_reliability(q, dds_kind(*qos.reliability), kMaxBlockingTime);
  dds_qset_durability(q, dds_kind(*qos.durability));
  const bool keep_all = qos.history == History::KeepAll;
  const auto kind = keep_all ? DDS_HISTORY_KEEP_ALL : DDS_HISTORY_KEEP_LAST;
  const std::int32_t depth =
      keep_all ? DDS_LENGTH_UNLIMITED : static_cast<std::int32_t>(*qos.depth);
  dds_qset_history(q, kind, depth);
  // What a late joiner is replayed: Cyclone keeps the durability service's depth (1 by default),
  // not the history's, for a transient-local writer.
  if (*qos.durability != Durability::Volatile)
    dds_qset_durability_service(q, 0, kind, depth, DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED,
                                DDS_LENGTH_UNLIMITED);
  dds_qset_deadline(q, dds_duration(*qos.deadline));
  dds_qset_latency_budget(q, dds_duration(*qos.latency_budget));
  dds_qset_transport_priority(q, *qos.transport_priority);
  dds_qset_liveliness(q, dds_kind(*qos.liveliness), dds_duration(*qos.lease));
  dds_qset_ownership(q, qos.ownership == Ownership::Exclusive ? DDS_OWNERSHIP_EXCLUSIVE
                                                              : DDS_OWNERSHIP_SHARED);
  dds_qset_ownership_strength(q, *qos.strength);
  return out;
}

} // namespace

nlohmann::json qos_to_json(const ConnectionQos &given) {
  const ConnectionQos qos = with_defaults(given);
  Json json = {
      {"reliability", profile::to_string(*qos.reliability)},
      {"durability", profile::to_string(*qos.durability)},
      {"history", profile::to_string(*qos.history)},
      {"deadline_ns", duration_json(*qos.deadline)},
      {"latencybudget_ns", duration_json(*qos.latency_budget)},
      {"transportpriority", *qos.transport_priority},
      {"liveliness", profile::to_string(*qos.liveliness)},
      {"lease_ns", duration_json(*qos.lease)},
      {"ownership", profile::to_string(*qos.ownership)},
      {"strength", *qos.strength},
      {"transport", profile::to_string(*qos.transport)},
  };
  if (qos.depth)
    json["depth"] = *qos.depth;
  return json;
}

Expected<profile::ConnectionQos> connection_qos_from_json(const nlohmann::json &json) {
  return parse(json);
}

Expected<Qos> qos_from_json(const nlohmann::json &json) {
  return parse(json).map(make_dds_qos);
}

std::optional<std::string> qos_incompatibility(const ConnectionQos &offered_qos,
                                               const ConnectionQos &requested_qos) {
  const ConnectionQos o = with_defaults(offered_qos), r = with_defaults(requested_qos);
  auto mismatch = [](const char *policy, auto offered, auto requested) {
    return fmt::format("{}: the writer offers {}, the reader requests {}", policy, offered,
                       requested);
  };
  if (*o.reliability < *r.reliability)
    return mismatch("reliability", profile::to_string(*o.reliability),
                    profile::to_string(*r.reliability));
  if (*o.durability < *r.durability)
    return mismatch("durability", profile::to_string(*o.durability),
                    profile::to_string(*r.durability));
  if (longer(*o.deadline, *r.deadline))
    return mismatch("deadline", duration_text(*o.deadline), duration_text(*r.deadline));
  if (longer(*o.latency_budget, *r.latency_budget))
    return mismatch("latency budget", duration_text(*o.latency_budget),
                    duration_text(*r.latency_budget));
  if (*o.liveliness < *r.liveliness)
    return mismatch("liveliness", profile::to_string(*o.liveliness),
                    profile::to_string(*r.liveliness));
  if (longer(*o.lease, *r.lease))
    return mismatch("liveliness lease", duration_text(*o.lease), duration_text(*r.lease));
  if (*o.ownership != *r.ownership)
    return mismatch("ownership", profile::to_string(*o.ownership),
                    profile::to_string(*r.ownership));
  return std::nullopt;
}

} // namespace rsca::dds
