// The domain's own events: nodes and devices coming and going, applications created and
// released, components exiting unexpectedly, connection problems. Published as PropertyEvents
// ({source: "domain", id: kind, value: JSON details}) on the domain's event topic, which
// `rsca events` follows live. The writer keeps the last events for late followers.
#pragma once

#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "common/diagnostic.hpp"
#include "dds/entity.hpp"
#include "dds/participant.hpp"

namespace rsca::control {

// The DDS topic of the domain's events: protocol::domain_events_topic.

// How many past events a late follower still receives.
inline constexpr int kKeptDomainEvents = 64;

class DomainEvents {
public:
  static Expected<std::unique_ptr<DomainEvents>> open(std::shared_ptr<dds::Participant> participant,
                                                      const std::string &domain);
  // Publishes one event; never blocks on followers (keep-last history).
  void publish(const std::string &kind, const nlohmann::json &details);

  DomainEvents(std::shared_ptr<dds::Participant> participant, dds::Entity topic, dds::Entity writer)
      : participant_(std::move(participant)), topic_(std::move(topic)), writer_(std::move(writer)) {
  }

private:
  std::shared_ptr<dds::Participant> participant_;
  dds::Entity topic_;
  dds::Entity writer_;
  std::mutex mutex_;
};

struct DomainEvent {
  std::uint64_t timestamp_ns = 0; // CLOCK_REALTIME
  std::string kind;               // "node.added", "application.created", ...
  nlohmann::json details;
};

// Follows the domain's events: the last kKeptDomainEvents first, then each as it comes.
class DomainEventFollower {
public:
  static Expected<std::unique_ptr<DomainEventFollower>>
  open(std::shared_ptr<dds::Participant> participant, const std::string &domain);
  // Waits until the domain's event writer is found; false when `timeout` passes first. The
  // domain's last events arrive soon after.
  bool wait_for_domain(std::chrono::milliseconds timeout);
  // The next event, or nothing when `timeout` passes first.
  std::optional<DomainEvent> next(std::chrono::milliseconds timeout);

  DomainEventFollower(std::shared_ptr<dds::Participant> participant, dds::Entity topic,
                      dds::Entity reader, dds::Entity waitset)
      : participant_(std::move(participant)), topic_(std::move(topic)), reader_(std::move(reader)),
        waitset_(std::move(waitset)) {}

private:
  std::optional<DomainEvent> take();

  std::shared_ptr<dds::Participant> participant_;
  dds::Entity topic_;
  dds::Entity reader_;
  dds::Entity waitset_;
};

// The QoS of the domain's event topic, writer and readers alike: reliable, transient-local,
// keep the last kKeptDomainEvents.
dds::Qos domain_events_qos();

} // namespace rsca::control
