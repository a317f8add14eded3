// Private to the component runtime: one connection of a data port (component/ports.hpp), and
// how its ends count the QoS problems DDS would count for them (port_problems.cpp).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "common/content_filter.hpp"
#include "component/liveliness_ticker.hpp"
#include "component/local_topics.hpp"
#include "component/ports.hpp"
#include "component/receive_loop.hpp"
#include "component/tcp_stream.hpp"
#include "dds/entity.hpp"
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
  // A reader whose DDS listener delivers on its own thread (Delivery::Listener): its port.
  PortBase *listened_by = nullptr;
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
  std::int64_t deadline_gap_ns = 0; // provides: the last_sample_ns that gap began at (same)
  bool watched = false; // a reader with a deadline or a liveliness lease: problems to look for
  bool durable = false; // a transient-local reader: what arrives before the start is kept
  // A keep-last reader: what arrives while its component is stopped stays in the history (the
  // newest `depth`: DDS's, the ring's, the inbox's) and is delivered at the start, as a reader
  // that is merely busy would get it.
  bool keep_last = false;
  std::uint64_t held_arrivals = 0; // the ring's or inbox's count at the last look while stopped

  // Same-host: the ring's writer or reader; the deadline as in-host. Lost writers already
  // reported (provides, receive thread).
  std::optional<shm::RingWriter> ring_writer;
  std::optional<shm::RingReader> ring_reader;
  std::uint32_t writers_lost_reported = 0;
  // The liveliness lease a ring reader checks, or a ring writer's ticker asserts (0: none), and
  // its kind (a manual writer asserts by writing).
  std::chrono::nanoseconds lease{0};
  profile::Liveliness liveliness = profile::Liveliness::Automatic;
  // The ring's alive_ns when lost liveliness was last reported (receive thread): a gap is
  // reported once, however it was seen.
  std::int64_t lost_at_alive_ns = -1;
  bool ticking = false; // the writer's liveliness is asserted by the ticker
  bool relayed = false; // the node relays the ring to and from other hosts

  // A TCP stream (transport="tcp"): the writer's end, or the reader's, whose thread fills
  // `inbox` or delivers on itself (Delivery::Listener). Last: destroyed first, so its thread has
  // stopped before what it uses goes.
  std::unique_ptr<TcpSender> tcp_out;
  std::unique_ptr<TcpReceiver> tcp_in;

  ~DataConnection() {
    if (ticking)
      LivelinessTicker::instance().remove(&*ring_writer);
    if (loop != nullptr && entity)
      loop->detach(entity.get());
    tcp_in.reset(); // its thread stops before the inbox it fills goes
    if (local && inbox)
      local->remove_reader(inbox.get());
    else if (local)
      local->remove_writer();
  }

  bool in_host() const { return local != nullptr; }
  bool same_host() const { return ring_writer || ring_reader; }
  bool tcp() const { return tcp_out || tcp_in; }
  // Its ends count deadlines themselves, as DDS would (no DDS entity does it for them).
  bool own_deadline() const { return in_host() || same_host() || tcp(); }
};

} // namespace detail

namespace detail {

std::int64_t steady_ns();
// An in-host or same-host writer's offered deadline: the periods each gap between writes spanned.
void note_local_write(DataConnection &c);
// A reader whose component is stopped keeps what arrives untaken: an arrival still ends a
// deadline gap on the transports that count their own (DDS counts arrivals, not takes).
void note_held_arrivals(DataConnection &c);
// How often the writer (uses) or the reader's writers (provides) missed the connection's deadline.
std::uint32_t deadline_misses(const DataConnection &c, profile::PortDirection direction);
// The QoS the end applies, read back from its live transport (component/applied_qos.cpp);
// nothing when DDS cannot say.
std::optional<AppliedQos> applied_qos(const DataConnection &c);

} // namespace detail
} // namespace rsca::component
