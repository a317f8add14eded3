#include "component/ports.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "component/data_connection.hpp"
#include "component/filter_fields.hpp"
#include "component/port_record.hpp"
#include "component/port_wire.hpp"
#include "shm/process_arena.hpp"

namespace rsca::component {

namespace {

using detail::DataConnection;
using detail::deadline_misses;
using detail::note_local_write;
using detail::steady_ns;

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

// The data-available listener of a reader whose port delivers on the listener's thread: Cyclone's
// receive thread for a remote writer, the writer's own thread for one in this process.
void on_data_here(dds_entity_t, void *connection) {
  auto *c = static_cast<DataConnection *>(connection);
  c->listened_by->take_here(*c);
}

// Its own listener, with the connection as the argument (Cyclone copies the listener: it need
// not outlive the call). Detached as the loop's listener is (~DataConnection).
Expected<void> listen_here(DataConnection &c) {
  std::unique_ptr<dds_listener_t, decltype(&dds_delete_listener)> listener(dds_create_listener(&c),
                                                                           &dds_delete_listener);
  dds_lset_data_available(listener.get(), &on_data_here);
  if (dds_return_t rc = dds_set_listener(c.entity.get(), listener.get()); rc < 0)
    return tl::unexpected(dds::dds_error(rc, "setting a reader's listener"));
  c.loop->wake(); // what arrived before the listener was set
  return {};
}

// `listened_by`: the port, when its callback may run on the listener's thread.
Expected<std::unique_ptr<DataConnection>> open_reader(dds_entity_t participant,
                                                      detail::ReceiveLoop *loop,
                                                      std::unique_ptr<DataConnection> c,
                                                      const dds_qos_t *qos, PortBase *listened_by) {
  if (loop == nullptr)
    return make_error({"port", 0, 0}, "port", "no receive loop for a provides port");
  auto reader = dds::checked(dds_create_reader(participant, c->topic.get(), qos, nullptr),
                             fmt::format("creating a reader on topic \"{}\"", c->topic_name));
  if (!reader)
    return tl::unexpected(reader.error());
  c->entity = std::move(*reader);
  c->loop = loop;
  c->listened_by = listened_by;
  auto attached = listened_by ? listen_here(*c) : loop->attach(c->entity.get());
  if (!attached)
    return tl::unexpected(attached.error());
  // Deadline misses and lost liveliness are looked for by the loop's owner now and then
  // (take_problems), not waited for: a status check at every sample contends with Cyclone's
  // receive thread for the reader's locks.
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

profile::Liveliness liveliness_kind(const dds_qos_t *qos) {
  dds_liveliness_kind_t kind = DDS_LIVELINESS_AUTOMATIC;
  dds_duration_t lease = DDS_INFINITY;
  if (qos != nullptr)
    dds_qget_liveliness(qos, &kind, &lease);
  return kind == DDS_LIVELINESS_MANUAL_BY_TOPIC         ? profile::Liveliness::ManualByTopic
         : kind == DDS_LIVELINESS_MANUAL_BY_PARTICIPANT ? profile::Liveliness::ManualByParticipant
                                                        : profile::Liveliness::Automatic;
}

// Transient-local or more durable: the reader is owed the writer's history, and keeps what
// arrives before its component starts (DDS keeps it in the reader's history until taken).
bool durable(const dds_qos_t *qos) {
  dds_durability_kind_t kind = DDS_DURABILITY_VOLATILE;
  if (qos != nullptr)
    dds_qget_durability(qos, &kind);
  return kind != DDS_DURABILITY_VOLATILE;
}

// Whether a reader with this QoS can have problems to report (take_problems).
bool has_problems_to_watch(const dds_qos_t *qos) {
  return requested_deadline(qos).count() > 0 || liveliness_lease(qos).first.count() > 0;
}

std::int32_t matched_count(const DataConnection &c, profile::PortDirection direction) {
  if (c.tcp_out)
    return c.tcp_out->readers();
  if (c.tcp_in)
    return c.tcp_in->writers();
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

} // namespace

PortBase::PortBase(std::string name, profile::PortDirection direction, port::PortType type,
                   Delivery delivery)
    : name_(std::move(name)), direction_(direction), type_(type), delivery_(delivery) {}

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
  c->durable = direction_ == profile::PortDirection::Provides && durable(qos);
  c->keep_last = direction_ == profile::PortDirection::Provides && history_depth(qos) != 0;
  c->deadline = requested_deadline(qos); // what status reports; DDS counts its own misses
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
                    : open_reader(participant, loop, std::move(c), qos,
                                  delivery_ == Delivery::Listener ? this : nullptr);
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
  const auto [lease, automatic] = liveliness_lease(qos);
  c->lease = lease;
  c->liveliness = liveliness_kind(qos);
  if (direction_ == profile::PortDirection::Uses) {
    auto writer = shm::RingWriter::open(arena->arena(), ring.offset);
    if (!writer)
      return make_error({"port", 0, 0}, "port", writer.error());
    c->ring_writer.emplace(std::move(*writer));
    if (automatic) {
      detail::LivelinessTicker::instance().add(&*c->ring_writer, lease);
      c->ticking = true;
    }
    return c;
  }
  if (loop == nullptr || !loop->doorbell())
    return make_error({"port", 0, 0}, "port", "no receive loop in the host's arena to ring");
  const auto depth = static_cast<std::uint32_t>(history_depth(qos));
  // A transient-local reader starts at the last `depth` records the ring holds (all, keepall).
  const std::uint32_t history = c->durable ? (depth == 0 ? ~0U : depth) : 0;
  auto reader = shm::RingReader::open(arena->arena(), ring.offset, ring.slot, *loop->doorbell(),
                                      depth, /*skip_relayed=*/false, history);
  if (!reader)
    return make_error({"port", 0, 0}, "port", reader.error());
  c->ring_reader.emplace(std::move(*reader));
  c->writers_lost_reported = c->ring_reader->writers_lost();
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
                   c->same_host(), c->relayed, c->tcp(), detail::applied_qos(*c)});
  return out;
}

std::optional<std::int32_t> PortBase::matched(const std::string &connection) const {
  std::shared_lock lock(mutex_);
  auto it = connections_.find(connection);
  if (it == connections_.end())
    return std::nullopt;
  return matched_count(*it->second, direction_);
}

bool PortBase::watched() const {
  std::shared_lock lock(mutex_);
  return std::any_of(connections_.begin(), connections_.end(),
                     [](const auto &entry) { return entry.second->watched; });
}

void PortBase::take_all(bool) {}

void PortBase::take_here(DataConnection &c) {
  c.loop->wake();
}

void PortBase::take_frame(DataConnection &, const std::byte *, std::size_t) {}

Expected<std::string> PortBase::connect_tcp(detail::ReceiveLoop *loop,
                                            const std::string &connection, const dds_qos_t *qos,
                                            const std::string &peer, const std::string &token,
                                            std::chrono::milliseconds timeout) {
  auto c = std::make_unique<DataConnection>();
  c->topic_name = "tcp:" + connection;
  c->deadline = requested_deadline(qos);
  std::string endpoint;
  if (direction_ == profile::PortDirection::Uses) {
    auto sender = detail::TcpSender::connect(peer, token, timeout);
    if (!sender)
      return make_error({"port", 0, 0}, "port", sender.error());
    c->tcp_out = std::move(*sender);
  } else {
    if (loop == nullptr)
      return make_error({"port", 0, 0}, "port", "no receive loop for a provides port");
    c->loop = loop;
    c->watched = has_problems_to_watch(qos);
    c->keep_last = history_depth(qos) != 0;
    c->inbox = std::make_shared<detail::LocalInbox>(*loop, history_depth(qos));
    auto receiver = detail::TcpReceiver::listen(
        detail::listen_address(), token,
        [this, conn = c.get()](const std::byte *data, std::size_t bytes) {
          take_frame(*conn, data, bytes);
        });
    if (!receiver)
      return make_error({"port", 0, 0}, "port", receiver.error());
    endpoint = (*receiver)->endpoint();
    c->tcp_in = std::move(*receiver);
  }
  std::unique_lock lock(mutex_);
  connections_[connection] = std::move(c); // an earlier one of that id goes
  return endpoint;
}

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
    } else if (c->tcp_out) {
      auto ok = c->tcp_out->send(port::record::size_of(value), [&value](std::byte *at) {
        port::record::Writer w(at);
        port::record::write(value, w);
      });
      if (!ok) {
        failed(id, ok.error());
        continue;
      }
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
    if (!deliver && (c->durable || c->keep_last)) {
      note_held_arrivals(*c);
      continue; // kept for the component's start: the history it is owed, or the newest depth
    }
    if (c->in_host() || c->tcp_in)
      take_local(*c, deliver);
    else if (c->ring_reader)
      take_same_host(*c, deliver);
    else
      take_dds(*c, deliver);
  }
}

// Not waiting for the port's lock: a (dis)connect holds it, and a disconnect waits, in
// dds_set_listener, for this very call to end.
template <typename T>
void ProvidesPort<T>::take_here(DataConnection &c) {
  std::shared_lock lock(mutex_, std::try_to_lock);
  if (lock && c.loop->run_here([this, &c] { take_dds(c, true); }))
    return;
  c.loop->wake();
}

// A frame that is not a whole record of T is dropped: what the network sends is not trusted.
template <typename T>
void ProvidesPort<T>::take_frame(DataConnection &c, const std::byte *data, std::size_t bytes) {
  auto value = std::make_shared<T>();
  port::record::Reader r(data, bytes);
  if (!port::record::read(r, *value))
    return;
  if (delivery() == Delivery::Listener) {
    std::shared_lock lock(mutex_, std::try_to_lock);
    if (lock && c.loop->run_here([this, &c, &value] {
          c.last_sample_ns.store(steady_ns(), std::memory_order_relaxed);
          c.samples.fetch_add(1, std::memory_order_relaxed);
          if (callback_)
            this->deliver(c, *value);
        }))
      return;
  }
  c.inbox->push(std::move(value));
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
