#include "control/domain_events.hpp"

#include <cctype>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "ports.h" // generated from dds/ports.idl
#include "protocol/json_text.hpp"
#include "protocol/topics.hpp"

namespace rsca::control {
namespace {

std::uint64_t now_ns() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}

} // namespace

dds::Qos domain_events_qos() {
  auto qos = dds::make_qos();
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(qos.get(), DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, kKeptDomainEvents);
  // Cyclone keeps a transient-local writer's history for late readers by its durability-service
  // depth (1 by default), not by its history.
  dds_qset_durability_service(qos.get(), 0, DDS_HISTORY_KEEP_LAST, kKeptDomainEvents,
                              DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
  return qos;
}

namespace {

Expected<dds::Entity> events_topic(dds_entity_t participant, const std::string &domain) {
  const std::string name = protocol::domain_events_topic(domain);
  auto qos = domain_events_qos();
  return dds::checked(dds_create_topic(participant, &rsca_port_PropertyEvent_desc, name.c_str(),
                                       qos.get(), nullptr),
                      fmt::format("creating topic \"{}\"", name));
}

} // namespace

Expected<std::unique_ptr<DomainEventFollower>>
DomainEventFollower::open(std::shared_ptr<dds::Participant> participant,
                          const std::string &domain) {
  auto topic = events_topic(participant->get(), domain);
  if (!topic)
    return tl::unexpected(topic.error());
  auto qos = domain_events_qos();
  auto reader =
      dds::checked(dds_create_reader(participant->get(), topic->get(), qos.get(), nullptr),
                   "creating the domain events reader");
  if (!reader)
    return tl::unexpected(reader.error());
  auto waitset = dds::checked(dds_create_waitset(participant->get()), "creating a waitset");
  if (!waitset)
    return tl::unexpected(waitset.error());
  dds_set_status_mask(reader->get(), DDS_DATA_AVAILABLE_STATUS);
  if (dds_return_t rc = dds_waitset_attach(waitset->get(), reader->get(), 0); rc < 0)
    return tl::unexpected(dds::dds_error(rc, "attaching the domain events reader"));
  return std::make_unique<DomainEventFollower>(std::move(participant), std::move(*topic),
                                               std::move(*reader), std::move(*waitset));
}

std::optional<DomainEvent> DomainEventFollower::take() {
  void *samples[1] = {nullptr};
  dds_sample_info_t info;
  for (;;) {
    const dds_return_t n = dds_take(reader_.get(), samples, &info, 1, 1);
    if (n <= 0)
      return std::nullopt;
    std::optional<DomainEvent> event;
    if (info.valid_data) {
      const auto *e = static_cast<const rsca_port_PropertyEvent *>(samples[0]);
      event = DomainEvent{e->timestamp_ns, e->id != nullptr ? e->id : "",
                          protocol::parse_json(e->value != nullptr ? e->value : "null")
                              .value_or(nlohmann::json(nlohmann::json::value_t::discarded))};
    }
    dds_return_loan(reader_.get(), samples, n);
    if (event)
      return event;
  }
}

bool DomainEventFollower::wait_for_domain(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  // The waitset wakes on a match alone while waiting here (data already there would wake it at
  // once, over and over), and on data alone in next().
  dds_set_status_mask(reader_.get(), DDS_SUBSCRIPTION_MATCHED_STATUS);
  bool matched = false;
  for (;;) {
    dds_subscription_matched_status_t status{};
    matched = dds_get_subscription_matched_status(reader_.get(), &status) == 0 &&
              status.current_count > 0;
    const auto left = deadline - std::chrono::steady_clock::now();
    if (matched || left <= std::chrono::steady_clock::duration::zero())
      break;
    dds_waitset_wait(waitset_.get(), nullptr, 0,
                     std::chrono::duration_cast<std::chrono::nanoseconds>(left).count());
  }
  dds_set_status_mask(reader_.get(), DDS_DATA_AVAILABLE_STATUS);
  return matched;
}

std::optional<DomainEvent> DomainEventFollower::next(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    if (auto event = take())
      return event;
    const auto left = deadline - std::chrono::steady_clock::now();
    if (left <= std::chrono::steady_clock::duration::zero())
      return std::nullopt;
    dds_waitset_wait(waitset_.get(), nullptr, 0,
                     std::chrono::duration_cast<std::chrono::nanoseconds>(left).count());
  }
}

Expected<std::unique_ptr<DomainEvents>>
DomainEvents::open(std::shared_ptr<dds::Participant> participant, const std::string &domain) {
  auto topic = events_topic(participant->get(), domain);
  if (!topic)
    return tl::unexpected(topic.error());
  auto qos = domain_events_qos();
  auto writer =
      dds::checked(dds_create_writer(participant->get(), topic->get(), qos.get(), nullptr),
                   "creating the domain events writer");
  if (!writer)
    return tl::unexpected(writer.error());
  return std::make_unique<DomainEvents>(std::move(participant), std::move(*topic),
                                        std::move(*writer));
}

void DomainEvents::publish(const std::string &kind, const nlohmann::json &details) {
  const std::string value = details.dump();
  rsca_port_PropertyEvent event{};
  event.timestamp_ns = now_ns();
  event.source = const_cast<char *>("domain");
  event.id = const_cast<char *>(kind.c_str());
  event.value = const_cast<char *>(value.c_str());
  std::lock_guard lock(mutex_);
  if (dds_return_t rc = dds_write(writer_.get(), &event); rc < 0)
    spdlog::warn("domain event {} not published: {}", kind, dds_strretcode(rc));
}

} // namespace rsca::control
