#include "profile/connection_qos.hpp"

#include <algorithm>
#include <charconv>
#include <limits>

#include <fmt/format.h>

namespace rsca::profile {
namespace {

using FieldResult = tl::expected<void, std::string>;

// `text` as one of `values`, by their names in the model (profile::to_string).
template <typename E, std::size_t N>
FieldResult set_enum(std::optional<E> &field, std::string_view text,
                     const std::array<E, N> &values) {
  for (E v : values)
    if (text == to_string(v)) {
      field = v;
      return {};
    }
  std::string names;
  for (E v : values)
    names += (names.empty() ? "" : ", ") + std::string(to_string(v));
  return tl::unexpected(fmt::format("not one of {}", names));
}

// `text` as an integer from `min` to the largest Int (xs:int for transportpriority and strength;
// xs:positiveInteger for depth, bounded by what DDS takes: an int32).
template <typename Int, typename Field>
FieldResult set_integer(std::optional<Field> &field, std::string_view text, Int min) {
  constexpr Int kMax = std::numeric_limits<Int>::max();
  Int value{};
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || value < min)
    return tl::unexpected(fmt::format("not an integer from {} to {}", min, kMax));
  field = static_cast<Field>(value);
  return {};
}

FieldResult set_duration(std::optional<Duration> &field, std::string_view text) {
  auto duration = parse_duration(text);
  if (!duration)
    return tl::unexpected(std::string(
        "not a duration such as 100ms, 1.5s or infinite (units ns, us, ms, s; at most about 292 "
        "years)"));
  field = *duration;
  return {};
}

} // namespace

bool is_qos_attribute(std::string_view name) {
  return std::find(kQosAttributes.begin(), kQosAttributes.end(), name) != kQosAttributes.end();
}

FieldResult set_qos_attribute(ConnectionQos &qos, std::string_view name, std::string_view text) {
  constexpr auto kInt32Min = std::numeric_limits<std::int32_t>::min();
  if (name == "reliability")
    return set_enum(qos.reliability, text,
                    std::array{Reliability::BestEffort, Reliability::Reliable});
  if (name == "durability")
    return set_enum(qos.durability, text,
                    std::array{Durability::Volatile, Durability::TransientLocal,
                               Durability::Transient, Durability::Persistent});
  if (name == "history")
    return set_enum(qos.history, text, std::array{History::KeepLast, History::KeepAll});
  if (name == "depth")
    return set_integer<std::int32_t>(qos.depth, text, 1);
  if (name == "deadline")
    return set_duration(qos.deadline, text);
  if (name == "latencybudget")
    return set_duration(qos.latency_budget, text);
  if (name == "transportpriority")
    return set_integer<std::int32_t>(qos.transport_priority, text, kInt32Min);
  if (name == "liveliness")
    return set_enum(qos.liveliness, text,
                    std::array{Liveliness::Automatic, Liveliness::ManualByParticipant,
                               Liveliness::ManualByTopic});
  if (name == "lease")
    return set_duration(qos.lease, text);
  if (name == "ownership")
    return set_enum(qos.ownership, text, std::array{Ownership::Shared, Ownership::Exclusive});
  if (name == "strength")
    return set_integer<std::int32_t>(qos.strength, text, kInt32Min);
  if (name == "transport")
    return set_enum(qos.transport, text,
                    std::array{Transport::Node, Transport::Direct, Transport::Tcp});
  return tl::unexpected(std::string("not a QoS attribute"));
}

std::optional<std::string> qos_inconsistency(const ConnectionQos &qos) {
  if (qos.depth && qos.history == History::KeepAll)
    return "depth applies only to history=\"keeplast\", not to keepall";
  if (qos.strength && qos.ownership != Ownership::Exclusive)
    return "strength applies only to ownership=\"exclusive\"";
  if (qos.transport)
    return not_honoured(qos, *qos.transport);
  return std::nullopt;
}

TransportHonours honours(Transport transport) {
  switch (transport) {
  case Transport::Direct:
    return {Durability::Persistent, true, true, true};
  case Transport::Node: // a reader replays the ring's last records (shm/ring.hpp)
    return {Durability::TransientLocal, false, false, true};
  case Transport::Tcp: // a stream keeps nothing for a later stream
    return {Durability::Volatile, false, false, false};
  }
  return {Durability::Volatile, false, false, false};
}

std::optional<std::string> not_honoured(const ConnectionQos &qos, Transport transport) {
  const TransportHonours can = honours(transport);
  const auto refused = [transport](std::string_view asked, std::string_view why) {
    return fmt::format("transport=\"{}\" does not honour {} ({}): leave transport out (the "
                       "domain then takes direct DDS) or give transport=\"direct\"",
                       to_string(transport), asked, why);
  };
  // A TCP stream tells a closed connection, not a writer that stopped asserting itself.
  if (qos.lease && !qos.lease->infinite() && !can.liveliness_lease)
    return fmt::format("transport=\"{}\" carries no liveliness lease: use transport=\"node\" or "
                       "\"direct\"",
                       to_string(transport));
  const Durability durability = qos.durability.value_or(Durability::Volatile);
  if (durability > can.durability)
    return refused(fmt::format("durability=\"{}\"", to_string(durability)),
                   can.durability == Durability::Volatile
                       ? "it keeps nothing for a reader that joins later"
                       : "its history goes with the writer's node");
  if (qos.ownership == Ownership::Exclusive && !can.exclusive_ownership)
    return refused("ownership=\"exclusive\"", "it delivers every writer");
  if (qos.reliability.value_or(Reliability::Reliable) == Reliability::Reliable &&
      qos.history == History::KeepAll && !can.reliable_keep_all)
    return refused("reliability=\"reliable\" with history=\"keepall\"",
                   "a reader that falls behind would lose the oldest samples");
  return std::nullopt;
}

Transport transport_for(const ConnectionQos &qos) {
  return not_honoured(qos, Transport::Node) ? Transport::Direct : Transport::Node;
}

} // namespace rsca::profile
