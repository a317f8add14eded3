#include "control/partition_writers.hpp"

#include <algorithm>
#include <vector>

#include <fmt/format.h>

#include "protocol/addresses.hpp"

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

// Whether one of the writer's matched readers reads in `partition` (not merely in one its
// wildcard partition matches).
bool matched_reader_in(dds_entity_t writer, const std::string &partition) {
  constexpr std::size_t kMaxLooked = 256;
  dds_instance_handle_t handles[kMaxLooked];
  const dds_return_t n = dds_get_matched_subscriptions(writer, handles, kMaxLooked);
  for (dds_return_t i = 0; i < n && i < static_cast<dds_return_t>(kMaxLooked); ++i) {
    dds_builtintopic_endpoint_t *reader = dds_get_matched_subscription_data(writer, handles[i]);
    if (reader == nullptr)
      continue;
    std::uint32_t count = 0;
    char **names = nullptr;
    bool found = false;
    if (dds_qget_partition(reader->qos, &count, &names)) {
      for (std::uint32_t k = 0; k < count; ++k) {
        found = found || partition == names[k];
        dds_free(names[k]);
      }
      dds_free(names);
    }
    dds_builtintopic_free_endpoint(reader);
    if (found)
      return true;
  }
  return false;
}

bool matched(dds_entity_t writer, const std::string &partition, bool shared) {
  // Read in both cases: reading the status clears its trigger, which would otherwise wake the
  // waitset at once for ever after the first match.
  dds_publication_matched_status_t status{};
  const bool any =
      dds_get_publication_matched_status(writer, &status) == 0 && status.current_count > 0;
  if (!shared || !any)
    return any;
  return matched_reader_in(writer, partition);
}

// The shared way keeps the last replies only: with every CLI client's reader on one writer, one
// client that stops acknowledging must not make writes block (and fail) for all the others.
constexpr std::int32_t kSharedReplyHistory = 64;

} // namespace

PartitionWriters::PartitionWriters(dds_entity_t participant, dds_entity_t topic,
                                   const dds_qos_t *qos, std::size_t max_ways)
    : participant_(participant), topic_(topic), qos_(copy_of(qos)), max_ways_(max_ways) {}

CallResult<dds_entity_t> PartitionWriters::writer_for(const std::string &partition) {
  if (!protocol::is_plain_address(partition))
    return call_error(Status::BadRequest,
                      fmt::format("\"{}\" is no address: it holds '*' or '?'", partition));
  const auto shared = protocol::cli_clients_partition(partition);
  const std::string &way = shared ? *shared : partition;
  std::lock_guard lock(mutex_);
  if (auto it = ways_.find(way); it != ways_.end()) {
    it->second.used = Clock::now();
    return it->second.writer.get();
  }
  make_room_locked();
  auto pqos = partition_qos(way);
  auto publisher =
      dds::checked(dds_create_publisher(participant_, pqos.get(), nullptr), "creating a publisher");
  if (!publisher)
    return call_error(Status::Failed, publisher.error().to_string());
  auto wqos = copy_of(qos_.get());
  if (shared)
    dds_qset_history(wqos.get(), DDS_HISTORY_KEEP_LAST, kSharedReplyHistory);
  auto writer = dds::checked(dds_create_writer(publisher->get(), topic_, wqos.get(), nullptr),
                             "creating a writer");
  if (!writer)
    return call_error(Status::Failed, writer.error().to_string());
  dds_set_status_mask(writer->get(), DDS_PUBLICATION_MATCHED_STATUS);
  const dds_entity_t handle = writer->get();
  ways_.emplace(way, Way{std::move(*publisher), std::move(*writer), shared.has_value()});
  return handle;
}

CallResult<dds_entity_t> PartitionWriters::matched_writer(const std::string &partition,
                                                          Clock::time_point deadline,
                                                          const std::atomic<bool> &stopping) {
  auto writer = writer_for(partition);
  if (!writer)
    return writer;
  const bool shared = protocol::cli_clients_partition(partition).has_value();
  dds::Entity waitset(dds_create_waitset(participant_));
  dds_waitset_attach(waitset.get(), *writer, *writer);
  for (;;) {
    if (matched(*writer, partition, shared))
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
  ways_.erase(partition); // a shared way is named by its pattern, never by a caller's address
}

std::set<std::string> PartitionWriters::departed() const {
  std::lock_guard lock(mutex_);
  std::set<std::string> gone;
  for (const auto &[partition, way] : ways_)
    if (!way.shared && readers_left(way.writer.get()))
      gone.insert(partition);
  return gone;
}

std::size_t PartitionWriters::size() const {
  std::lock_guard lock(mutex_);
  return ways_.size();
}

std::optional<dds_entity_t> PartitionWriters::matched_way(const std::string &partition) {
  const auto shared = protocol::cli_clients_partition(partition);
  std::lock_guard lock(mutex_);
  auto it = ways_.find(shared ? *shared : partition);
  if (it == ways_.end() || !matched(it->second.writer.get(), partition, shared.has_value()))
    return std::nullopt;
  it->second.used = Clock::now();
  return it->second.writer.get();
}

std::size_t PartitionWriters::drop_unmatched(Clock::time_point unused_since,
                                             const std::set<std::string> &kept) {
  std::lock_guard lock(mutex_);
  return std::erase_if(ways_, [&](const auto &entry) {
    const auto &[partition, way] = entry;
    if (way.shared || way.used >= unused_since || kept.contains(partition))
      return false;
    dds_publication_matched_status_t status{};
    return dds_get_publication_matched_status(way.writer.get(), &status) == 0 &&
           status.total_count == 0;
  });
}

void PartitionWriters::make_room_locked() {
  std::erase_if(ways_, [](const auto &entry) {
    return !entry.second.shared && readers_left(entry.second.writer.get());
  });
  if (max_ways_ == 0 || ways_.size() < max_ways_)
    return;
  // The least recently used is a caller long gone or one that never read: a way of a caller
  // still calling was used a moment ago, so the one a handler is about to write through is
  // never the one dropped.
  auto oldest = ways_.end();
  for (auto it = ways_.begin(); it != ways_.end(); ++it)
    if (!it->second.shared && (oldest == ways_.end() || it->second.used < oldest->second.used))
      oldest = it;
  if (oldest != ways_.end())
    ways_.erase(oldest);
}

} // namespace rsca::control
