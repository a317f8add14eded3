#include "control/partition_writers.hpp"

#include <algorithm>
#include <vector>

#include <fmt/format.h>

namespace rsca::control {
namespace {

dds::Qos copy_of(const dds_qos_t *qos) {
  auto copy = dds::make_qos();
  dds_copy_qos(copy.get(), qos);
  return copy;
}

dds::Qos partition_qos(const std::string &partition) {
  auto qos = dds::make_qos();
  const char *names[] = {partition.c_str()};
  dds_qset_partition(qos.get(), 1, names);
  return qos;
}

// Whether the writer's readers have all left: it was matched, and is no longer.
bool readers_left(dds_entity_t writer) {
  dds_publication_matched_status_t status{};
  return dds_get_publication_matched_status(writer, &status) == 0 && status.total_count > 0 &&
         status.current_count == 0;
}

} // namespace

PartitionWriters::PartitionWriters(dds_entity_t participant, dds_entity_t topic,
                                   const dds_qos_t *qos)
    : participant_(participant), topic_(topic), qos_(copy_of(qos)) {}

CallResult<dds_entity_t> PartitionWriters::writer_for(const std::string &partition) {
  std::lock_guard lock(mutex_);
  if (auto it = ways_.find(partition); it != ways_.end())
    return it->second.writer.get();
  drop_departed_locked();
  auto pqos = partition_qos(partition);
  auto publisher =
      dds::checked(dds_create_publisher(participant_, pqos.get(), nullptr), "creating a publisher");
  if (!publisher)
    return call_error(Status::Failed, publisher.error().to_string());
  auto writer = dds::checked(dds_create_writer(publisher->get(), topic_, qos_.get(), nullptr),
                             "creating a writer");
  if (!writer)
    return call_error(Status::Failed, writer.error().to_string());
  dds_set_status_mask(writer->get(), DDS_PUBLICATION_MATCHED_STATUS);
  const dds_entity_t handle = writer->get();
  ways_.emplace(partition, Way{std::move(*publisher), std::move(*writer)});
  return handle;
}

CallResult<dds_entity_t> PartitionWriters::matched_writer(const std::string &partition,
                                                          Clock::time_point deadline,
                                                          const std::atomic<bool> &stopping) {
  auto writer = writer_for(partition);
  if (!writer)
    return writer;
  dds::Entity waitset(dds_create_waitset(participant_));
  dds_waitset_attach(waitset.get(), *writer, *writer);
  for (;;) {
    dds_publication_matched_status_t status{};
    if (dds_get_publication_matched_status(*writer, &status) == 0 && status.current_count > 0)
      return writer;
    const auto left = deadline - Clock::now();
    if (left <= Clock::duration::zero() || stopping.load())
      return call_error(Status::Unavailable, fmt::format("no endpoint at address {}", partition));
    dds_waitset_wait(
        waitset.get(), nullptr, 0,
        std::min<dds_duration_t>(
            DDS_MSECS(100), std::chrono::duration_cast<std::chrono::nanoseconds>(left).count()));
  }
}

void PartitionWriters::erase(const std::string &partition) {
  std::lock_guard lock(mutex_);
  ways_.erase(partition);
}

std::set<std::string> PartitionWriters::departed() const {
  std::lock_guard lock(mutex_);
  std::set<std::string> gone;
  for (const auto &[partition, way] : ways_)
    if (readers_left(way.writer.get()))
      gone.insert(partition);
  return gone;
}

std::size_t PartitionWriters::size() const {
  std::lock_guard lock(mutex_);
  return ways_.size();
}

void PartitionWriters::drop_departed_locked() {
  std::erase_if(ways_, [](const auto &entry) { return readers_left(entry.second.writer.get()); });
}

} // namespace rsca::control
