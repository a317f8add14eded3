#include "component/ports.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "component/filter_fields.hpp"
#include "component/liveliness_ticker.hpp"
#include "component/local_topics.hpp"
#include "component/port_record.hpp"
#include "component/port_wire.hpp"
#include "component/receive_loop.hpp"
#include "shm/process_arena.hpp"
#include "shm/ring.hpp"

namespace rsca::component {

namespace detail {

// One connection of a port: its topic and its writer or reader, or its in-host topic. The reader
// leaves the receive loop (or its inbox the topic) first, then members are destroyed in reverse
// order: the reader or writer, then the topic.
struct DataConnection {
  std::string topic_name;
  dds::Entity topic;
  dds::Entity entity; // the writer (uses) or reader (provides)
  ReceiveLoop *loop = nullptr;
  std::atomic<std::uint64_t> samples{0};
  std::optional<ContentFilter> filter; // provides only: what is delivered
  std::atomic<std::uint64_t> filtered{0};

  // In-host: the topic, a reader's inbox, and the deadline, which each end checks itself as DDS
  // would (requested by the reader, offered by the writer).
  std::shared_ptr<LocalTopic> local;
  std::shared_ptr<LocalInbox> inbox;
  std::chrono::nanoseconds deadline{0};
  // The last write (uses) or arrival (provides), steady clock ns; 0: none yet.
  std::atomic<std::int64_t> last_sample_ns{0};
  std::atomic<std::uint32_t> deadline_missed{0};
  std::uint32_t deadline_periods_reported = 0; // provides: of the current gap (receive thread)
  bool watched = false; // a reader with a deadline or a liveliness lease: problems to look for

  // Same-host: the ring's writer or reader; the deadline as in-host. Lost writers already
  // reported (provides, receive thread).
  std::optional<shm::RingWriter> ring_writer;
  std::optional<shm::RingReader> ring_reader;
  std::uint32_t writers_lost_reported = 0;
  std::chrono::nanoseconds lease{0}; // a reader's liveliness lease (0: none)
  // The ring's alive_ns when lost liveliness was last reported (receive thread): a gap is
  // reported once, however it was seen.
  std::int64_t lost_at_alive_ns = -1;
  bool ticking = false; // the writer's liveliness is asserted by the ticker
  bool relayed = false; // the node relays the ring to and from other hosts

  ~DataConnection() {
    if (ticking)
      LivelinessTicker::instance().remove(&*ring_writer);
    if (loop != nullptr && entity)
      loop->detach(entity.get());
    if (local && inbox)
      local->remove_reader(inbox.get());
    else if (local)
      local->remove_writer();
  }

  bool in_host() const { return local != nullptr; }
  bool same_host() const { return ring_writer || ring_reader; }
  // Its ends count deadlines themselves, as DDS would (no DDS entity does it for them).
  bool own_deadline() const { return in_host() || same_host(); }
};

} // namespace detail

namespace {

using detail::DataConnection;

constexpr std::uint32_t kTakeBatch = 32;

Expected<std::unique_ptr<DataConnection>>
open_writer(dds_entity_t participant, std::unique_ptr<DataConnection> c, const dds_qos_t *qos) {
  auto writer = dds::checked(dds_create_writer(participant, c->topic.get(), qos, nullptr),
                             fmt::format("creating a writer on topic \"{}\"", c->topic_name));
  if (!writer)
    return tl::unexpected(writer.error());
  c->entity = std::move(*writer);
  return c;
}

Expected<std::unique_ptr<DataConnection>> open_reader(dds_entity_t participant,
                                                      detail::ReceiveLoop *loop,
                                                      std::unique_ptr<DataConnection> c,
                                                      const dds_qos_t *qos) {
  if (loop == nullptr)
    return make_error({"port", 0, 0}, "port", "no receive loop for a provides port");
  auto reader = dds::checked(dds_create_reader(participant, c->topic.get(), qos, nullptr),
                             fmt::format("creating a reader on topic \"{}\"", c->topic_name));
  if (!reader)
    return tl::unexpected(reader.error());
  c->entity = std::move(*reader);
  if (auto attached = loop->attach(c->entity.get()); !attached)
    return tl::unexpected(attached.error());
  // Deadline misses and lost liveliness are looked for by the loop's owner now and then
  // (take_problems), not waited for: a status check at every sample contends with Cyclone's
  // receive thread for the reader's locks.
  c->loop = loop;
  return c;
}

// A reader's history depth (0: keep all), and the deadline (0: none), for in-host connections.
std::size_t history_depth(const dds_qos_t *qos) {
  dds_history_kind_t kind = DDS_HISTORY_KEEP_LAST;
  std::int32_t depth = 1;
  if (qos != nullptr)
    dds_qget_history(qos, &kind, &depth);
  return kind == DDS_HISTORY_KEEP_ALL ? 0 : static_cast<std::size_t>(std::max(1, depth));
}

std::chrono::nanoseconds requested_deadline(const dds_qos_t *qos) {
  dds_duration_t deadline = DDS_INFINITY;
  if (qos == nullptr || !dds_qget_deadline(qos, &deadline) || deadline == DDS_INFINITY)
    return std::chrono::nanoseconds{0};
  return std::chrono::nanoseconds{deadline};
}

// The liveliness lease a connection asks for (0: none), and whether it is automatic.
std::pair<std::chrono::nanoseconds, bool> liveliness_lease(const dds_qos_t *qos) {
  dds_liveliness_kind_t kind = DDS_LIVELINESS_AUTOMATIC;
  dds_duration_t lease = DDS_INFINITY;
  if (qos != nullptr)
    dds_qget_liveliness(qos, &kind, &lease);
  if (lease == DDS_INFINITY)
    return {std::chrono::nanoseconds{0}, false};
  return {std::chrono::nanoseconds{lease}, kind == DDS_LIVELINESS_AUTOMATIC};
}

// Whether a reader with this QoS can have problems to report (take_problems).
bool has_problems_to_watch(const dds_qos_t *qos) {
  return requested_deadline(qos).count() > 0 || liveliness_lease(qos).first.count() > 0;
}

std::int32_t matched_count(const DataConnection &c, profile::PortDirection direction) {
  if (c.ring_writer)
    return c.ring_writer->readers();
  if (c.ring_reader)
    return c.ring_reader->writers();
  if (c.in_host())
    return direction == profile::PortDirection::Uses ? c.local->readers() : c.local->writers();
  const dds_entity_t entity = c.entity.get();
  if (direction == profile::PortDirection::Uses) {
    dds_publication_matched_status_t status{};
    return dds_get_publication_matched_status(entity, &status) == 0
               ? static_cast<std::int32_t>(status.current_count)
               : 0;
  }
  dds_subscription_matched_status_t status{};
  return dds_get_subscription_matched_status(entity, &status) == 0
             ? static_cast<std::int32_t>(status.current_count)
             : 0;
}

std::int64_t steady_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// Whole deadline periods from `since_ns` to `now_ns`.
std::uint32_t periods_between(std::int64_t since_ns, std::int64_t now_ns,
                              std::chrono::nanoseconds deadline) {
  if (since_ns == 0 || deadline.count() <= 0 || now_ns <= since_ns)
    return 0;
  return static_cast<std::uint32_t>((now_ns - since_ns) / deadline.count());
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

// An in-host reader's requested deadline, counted as DDS counts it (once a sample has arrived,
// each period without one): the periods of the current gap not reported yet.
std::uint32_t local_deadline_misses(DataConnection &c) {
  const auto periods =
      periods_between(c.last_sample_ns.load(std::memory_order_relaxed), steady_ns(), c.deadline);
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

} // namespace

PortBase::PortBase(std::string name, profile::PortDirection direction, port::PortType type)
    : name_(std::move(name)), direction_(direction), type_(type) {}

PortBase::~PortBase() {
  disconnect_all();
}

std::size_t PortBase::connection_count() const {
  std::shared_lock lock(mutex_);
  return connections_.size();
}

Expected<void> PortBase::connect(dds_entity_t participant, detail::ReceiveLoop *loop,
                                 const std::string &connection, const std::string &topic,
                                 const dds_qos_t *qos, std::optional<ContentFilter> filter,
                                 bool local, std::optional<RingRef> ring) {
  auto c = std::make_unique<DataConnection>();
  c->topic_name = topic;
  c->filter = std::move(filter);
  c->watched = direction_ == profile::PortDirection::Provides && has_problems_to_watch(qos);
  if (local || ring) {
    auto opened = local ? open_local(loop, std::move(c), qos)
                        : open_same_host(loop, std::move(c), qos, *ring);
    if (!opened)
      return tl::unexpected(opened.error());
    std::unique_lock lock(mutex_);
    connections_[connection] = std::move(*opened);
    lock.unlock();
    // What arrived before the reader's doorbell was rung for it is looked for now.
    if (ring && loop != nullptr && direction_ == profile::PortDirection::Provides)
      loop->wake_in_host();
    return {};
  }
  auto created = dds::checked(
      dds_create_topic(participant, port::wire::descriptor(type_), topic.c_str(), nullptr, nullptr),
      fmt::format("creating topic \"{}\"", topic));
  if (!created)
    return tl::unexpected(created.error());
  c->topic = std::move(*created);
  auto opened = direction_ == profile::PortDirection::Uses
                    ? open_writer(participant, std::move(c), qos)
                    : open_reader(participant, loop, std::move(c), qos);
  if (!opened)
    return tl::unexpected(opened.error());
  std::unique_lock lock(mutex_);
  connections_[connection] = std::move(*opened); // an earlier one of that id goes
  return {};
}

Expected<std::unique_ptr<DataConnection>> PortBase::open_local(detail::ReceiveLoop *loop,
                                                               std::unique_ptr<DataConnection> c,
                                                               const dds_qos_t *qos) const {
  auto topic = detail::LocalTopics::instance().join(c->topic_name, type_);
  if (!topic)
    return make_error({"port", 0, 0}, "port", topic.error());
  c->local = std::move(*topic);
  c->deadline = requested_deadline(qos);
  if (direction_ == profile::PortDirection::Uses) {
    c->local->add_writer();
    return c;
  }
  if (loop == nullptr)
    return make_error({"port", 0, 0}, "port", "no receive loop for a provides port");
  c->inbox = std::make_shared<detail::LocalInbox>(*loop, history_depth(qos));
  c->local->add_reader(c->inbox);
  return c;
}

Expected<std::unique_ptr<DataConnection>>
PortBase::open_same_host(detail::ReceiveLoop *loop, std::unique_ptr<DataConnection> c,
                         const dds_qos_t *qos, const RingRef &ring) const {
  auto *arena = shm::ProcessArena::inherited();
  if (arena == nullptr)
    return make_error({"port", 0, 0}, "port",
                      "a same-host connection, but this process has no host arena from its node");
  c->deadline = requested_deadline(qos);
  c->relayed = ring.relayed;
  if (direction_ == profile::PortDirection::Uses) {
    auto writer = shm::RingWriter::open(arena->arena(), ring.offset);
    if (!writer)
      return make_error({"port", 0, 0}, "port", writer.error());
    c->ring_writer.emplace(std::move(*writer));
    if (auto [lease, automatic] = liveliness_lease(qos); automatic) {
      detail::LivelinessTicker::instance().add(&*c->ring_writer, lease);
      c->ticking = true;
    }
    return c;
  }
  if (loop == nullptr || !loop->doorbell())
    return make_error({"port", 0, 0}, "port", "no receive loop in the host's arena to ring");
  const auto depth = static_cast<std::uint32_t>(history_depth(qos));
  auto reader =
      shm::RingReader::open(arena->arena(), ring.offset, ring.slot, *loop->doorbell(), depth);
  if (!reader)
    return make_error({"port", 0, 0}, "port", reader.error());
  c->ring_reader.emplace(std::move(*reader));
  c->writers_lost_reported = c->ring_reader->writers_lost();
  c->lease = liveliness_lease(qos).first;
  return c;
}

bool PortBase::disconnect(const std::string &connection) {
  std::unique_lock lock(mutex_);
  return connections_.erase(connection) > 0;
}

void PortBase::disconnect_all() {
  std::unique_lock lock(mutex_);
  connections_.clear();
}

std::vector<ConnectionStatus> PortBase::status() const {
  std::shared_lock lock(mutex_);
  std::vector<ConnectionStatus> out;
  out.reserve(connections_.size());
  for (const auto &[id, c] : connections_)
    out.push_back({id, c->topic_name, matched_count(*c, direction_), c->samples.load(),
                   c->filtered.load(), deadline_misses(*c, direction_), c->in_host(),
                   c->same_host(), c->relayed});
  return out;
}

std::optional<std::int32_t> PortBase::matched(const std::string &connection) const {
  std::shared_lock lock(mutex_);
  auto it = connections_.find(connection);
  if (it == connections_.end())
    return std::nullopt;
  return matched_count(*it->second, direction_);
}

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

bool PortBase::watched() const {
  std::shared_lock lock(mutex_);
  return std::any_of(connections_.begin(), connections_.end(),
                     [](const auto &entry) { return entry.second->watched; });
}

void PortBase::take_all(bool) {}

void PortBase::quiesce() {
  std::unique_lock lock(mutex_);
}

template <typename T>
WriteResult PortBase::write_all(const T &value) {
  std::shared_lock lock(mutex_);
  std::size_t written = 0;
  std::string error;
  auto failed = [&](const std::string &id, const std::string &why) {
    if (error.empty())
      error = fmt::format("port {}: writing to connection {} failed: {}", name_, id, why);
  };
  std::optional<typename port::wire::Traits<T>::C> wire; // made for the first DDS connection
  std::shared_ptr<const void> shared;                    // one copy for every in-host reader
  for (const auto &[id, c] : connections_) {
    if (c->in_host()) {
      if (!shared)
        shared = std::make_shared<const T>(value);
      c->local->publish(shared);
    } else if (c->ring_writer) {
      auto ok = c->ring_writer->write(port::record::size_of(value), [&value](std::byte *at) {
        port::record::Writer w(at);
        port::record::write(value, w);
      });
      if (!ok) {
        failed(id, ok.error());
        continue;
      }
    } else {
      if (!wire)
        wire = port::wire::to_wire(value);
      if (const dds_return_t rc = dds_write(c->entity.get(), &*wire); rc < 0) {
        failed(id, dds_strretcode(rc));
        continue;
      }
    }
    if (c->own_deadline())
      note_local_write(*c);
    c->samples.fetch_add(1, std::memory_order_relaxed);
    ++written;
  }
  if (!error.empty())
    return tl::unexpected(std::move(error));
  return written;
}

template <typename T>
WriteResult UsesPort<T>::write(const T &value) {
  return write_all(value);
}

template <typename T>
void ProvidesPort<T>::take_all(bool deliver) {
  std::shared_lock lock(mutex_);
  for (const auto &[id, c] : connections_) {
    if (c->in_host())
      take_local(*c, deliver);
    else if (c->ring_reader)
      take_same_host(*c, deliver);
    else
      take_dds(*c, deliver);
  }
}

template <typename T>
void ProvidesPort<T>::take_dds(DataConnection &c, bool deliver) {
  using Wire = typename port::wire::Traits<T>::C;
  for (;;) {
    void *samples[kTakeBatch] = {nullptr};
    dds_sample_info_t infos[kTakeBatch];
    const dds_return_t n = dds_take(c.entity.get(), samples, infos, kTakeBatch, kTakeBatch);
    if (n <= 0)
      return;
    for (dds_return_t i = 0; i < n; ++i) {
      if (!infos[i].valid_data)
        continue;
      c.samples.fetch_add(1, std::memory_order_relaxed);
      if (!deliver || !callback_)
        continue;
      port::wire::from_wire(*static_cast<const Wire *>(samples[i]), scratch_);
      this->deliver(c, scratch_);
    }
    dds_return_loan(c.entity.get(), samples, n);
    // A short batch took all there was: another take would only contend with Cyclone's
    // receive thread for the reader's lock. What arrives later triggers the loop again.
    if (static_cast<std::uint32_t>(n) < kTakeBatch)
      return;
  }
}

template <typename T>
void ProvidesPort<T>::take_local(DataConnection &c, bool deliver) {
  auto arrived = c.inbox->take();
  if (arrived.empty())
    return;
  c.last_sample_ns.store(steady_ns(), std::memory_order_relaxed);
  c.deadline_periods_reported = 0;
  c.samples.fetch_add(arrived.size(), std::memory_order_relaxed);
  if (!deliver || !callback_)
    return;
  for (const auto &sample : arrived)
    this->deliver(c, *static_cast<const T *>(sample.get()));
}

template <typename T>
void ProvidesPort<T>::take_same_host(DataConnection &c, bool deliver) {
  const std::size_t arrived = c.ring_reader->take(
      [this](const std::byte *at, std::size_t bytes) {
        port::record::Reader r(at, bytes);
        return port::record::read(r, scratch_);
      },
      [this, &c, deliver] {
        c.samples.fetch_add(1, std::memory_order_relaxed);
        if (deliver && callback_)
          this->deliver(c, scratch_);
      });
  if (arrived == 0)
    return;
  c.last_sample_ns.store(steady_ns(), std::memory_order_relaxed);
  c.deadline_periods_reported = 0;
}

template <typename T>
void ProvidesPort<T>::deliver(DataConnection &c, const T &value) {
  if (c.filter &&
      !c.filter->matches([&value](std::string_view f) { return detail::field_of(value, f); })) {
    c.filtered.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  try {
    callback_(value);
  } catch (const std::exception &e) {
    spdlog::error("port {}: the sample callback failed: {}", name(), e.what());
  }
}

template class UsesPort<port::Samples>;
template class UsesPort<port::PropertyEvent>;
template class UsesPort<port::Command>;
template class ProvidesPort<port::Samples>;
template class ProvidesPort<port::PropertyEvent>;
template class ProvidesPort<port::Command>;

} // namespace rsca::component
