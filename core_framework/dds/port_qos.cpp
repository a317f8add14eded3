#include "dds/port_qos.hpp"

#include <array>
#include <limits>

#include <fmt/format.h>

namespace rsca::dds {
namespace {

using Json = nlohmann::json;
using profile::ConnectionQos;
using profile::Durability;
using profile::History;
using profile::Liveliness;
using profile::Ownership;
using profile::Reliability;

constexpr const char *kInfinite = "infinite";
constexpr dds_duration_t kMaxBlockingTime = DDS_MSECS(100);

constexpr std::array kKeys{"reliability", "durability",       "history",           "depth",
                           "deadline_ns", "latencybudget_ns", "transportpriority", "liveliness",
                           "lease_ns",    "ownership",        "strength"};

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

template <typename E, std::size_t N>
Expected<E> enum_from_json(const Json &json, const char *key, const std::array<E, N> &values) {
  std::string names;
  for (E v : values) {
    if (json.is_string() && json.get_ref<const std::string &>() == profile::to_string(v))
      return v;
    names += (names.empty() ? "" : ", ") + std::string(profile::to_string(v));
  }
  return qos_error(fmt::format("\"{}\" is {}, not one of {}", key, json.dump(), names));
}

Expected<Duration> duration_from_json(const Json &json, const char *key) {
  if (json.is_string() && json.get_ref<const std::string &>() == kInfinite)
    return Duration{};
  if (json.is_number_integer() && json.get<std::int64_t>() >= 0 &&
      !(json.is_number_unsigned() &&
        json.get<std::uint64_t>() > std::uint64_t(std::numeric_limits<std::int64_t>::max())))
    return Duration{std::chrono::nanoseconds(json.get<std::int64_t>())};
  return qos_error(
      fmt::format("\"{}\" is {}, not whole nanoseconds or \"infinite\"", key, json.dump()));
}

// Whether an integer JSON number (received numbers >= 0 are unsigned) lies in [min, max].
bool within(const Json &json, std::int64_t min, std::int64_t max) {
  if (json.is_number_unsigned()) {
    const auto value = json.get<std::uint64_t>();
    return value <= static_cast<std::uint64_t>(max) &&
           (min <= 0 || value >= static_cast<std::uint64_t>(min));
  }
  const auto value = json.get<std::int64_t>();
  return value >= min && value <= max;
}

template <typename T>
Expected<T> integer_from_json(const Json &json, const char *key, T min) {
  constexpr T kMax = std::numeric_limits<T>::max();
  if (json.is_number_integer() && within(json, min, kMax))
    return json.get<T>();
  return qos_error(
      fmt::format("\"{}\" is {}, not an integer from {} to {}", key, json.dump(), min, kMax));
}

Expected<void> check_keys(const Json &json) {
  if (!json.is_object())
    return qos_error(fmt::format("the QoS is {}, not an object", json.dump()));
  for (const auto &[key, value] : json.items()) {
    bool known = false;
    for (const char *k : kKeys)
      known = known || key == k;
    if (!known)
      return qos_error(fmt::format("unknown QoS \"{}\"", key));
  }
  return {};
}

// Reads `key` into `field` when present: `parse` gives the value or the error.
template <typename T, typename Parse>
Expected<void> read(const Json &json, const char *key, std::optional<T> &field, Parse parse) {
  auto it = json.find(key);
  if (it == json.end())
    return {};
  Expected<T> value = parse(*it, key);
  if (!value)
    return tl::unexpected(value.error());
  field = *value;
  return {};
}

Expected<ConnectionQos> parse(const Json &json) {
  ConnectionQos qos;
  auto reliability = [](const Json &j, const char *k) {
    return enum_from_json(j, k, std::array{Reliability::BestEffort, Reliability::Reliable});
  };
  auto durability = [](const Json &j, const char *k) {
    return enum_from_json(j, k,
                          std::array{Durability::Volatile, Durability::TransientLocal,
                                     Durability::Transient, Durability::Persistent});
  };
  auto history = [](const Json &j, const char *k) {
    return enum_from_json(j, k, std::array{History::KeepLast, History::KeepAll});
  };
  auto liveliness = [](const Json &j, const char *k) {
    return enum_from_json(j, k,
                          std::array{Liveliness::Automatic, Liveliness::ManualByParticipant,
                                     Liveliness::ManualByTopic});
  };
  auto ownership = [](const Json &j, const char *k) {
    return enum_from_json(j, k, std::array{Ownership::Shared, Ownership::Exclusive});
  };
  auto depth = [](const Json &j, const char *k) {
    return integer_from_json<std::int32_t>(j, k, 1).map(
        [](std::int32_t v) { return static_cast<std::uint32_t>(v); });
  };
  auto int32 = [](const Json &j, const char *k) {
    return integer_from_json<std::int32_t>(j, k, std::numeric_limits<std::int32_t>::min());
  };
  auto ok =
      check_keys(json)
          .and_then([&] { return read(json, "reliability", qos.reliability, reliability); })
          .and_then([&] { return read(json, "durability", qos.durability, durability); })
          .and_then([&] { return read(json, "history", qos.history, history); })
          .and_then([&] { return read(json, "depth", qos.depth, depth); })
          .and_then([&] { return read(json, "deadline_ns", qos.deadline, duration_from_json); })
          .and_then([&] {
            return read(json, "latencybudget_ns", qos.latency_budget, duration_from_json);
          })
          .and_then([&] { return read(json, "transportpriority", qos.transport_priority, int32); })
          .and_then([&] { return read(json, "liveliness", qos.liveliness, liveliness); })
          .and_then([&] { return read(json, "lease_ns", qos.lease, duration_from_json); })
          .and_then([&] { return read(json, "ownership", qos.ownership, ownership); })
          .and_then([&] { return read(json, "strength", qos.strength, int32); });
  if (!ok)
    return tl::unexpected(ok.error());
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
  if (qos.history == History::KeepAll)
    dds_qset_history(q, DDS_HISTORY_KEEP_ALL, DDS_LENGTH_UNLIMITED);
  else
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, static_cast<std::int32_t>(*qos.depth));
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
