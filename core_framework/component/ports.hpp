// Data ports of a component. A uses port writes, a provides port receives; each has zero or more
// connections, made and removed by the domain (component.connect/disconnect). A connection is a
// DDS writer (uses) or reader (provides) on the topic the domain names, with the QoS it gives;
// between two components of one component host it is an in-host connection instead, which
// bypasses DDS (component/local_topics.hpp), and between two processes of one host it is a
// same-host connection, a ring in the host's shared memory that the node made (shm/ring.hpp),
// each with the same API and QoS semantics.
// Writing to an unconnected uses port does nothing; with several connections a write goes to
// each. A provides port's callback runs on the component's receive thread, or, for a port that
// opts in (Delivery::Listener), on the DDS listener's thread when it can.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <shared_mutex>
#include <string>
#include <vector>

#include <tl/expected.hpp>

#include "common/content_filter.hpp"
#include "common/diagnostic.hpp"
#include "component/port_types.hpp"
#include "dds/entity.hpp"
#include "profile/assembly.hpp"
#include "profile/scd.hpp"

namespace rsca::component {

namespace detail {
struct DataConnection;
class ReceiveLoop;
} // namespace detail

// The QoS one end of a connection applies, read back from its live transport: a DDS reader's or
// writer's own QoS (dds_get_qos), or the settings a ring, TCP stream or in-host inbox was opened
// with. What the domain lists as the end's "qos", so that a QoS is checked where it acts.
struct AppliedQos {
  profile::Reliability reliability = profile::Reliability::Reliable;
  profile::History history = profile::History::KeepLast;
  std::int32_t depth = 0; // keeplast: the samples kept
  profile::Durability durability = profile::Durability::Volatile;
  profile::Ownership ownership = profile::Ownership::Shared;
  std::int64_t deadline_ns = 0; // 0: none
  profile::Liveliness liveliness = profile::Liveliness::Automatic;
  std::int64_t lease_ns = 0; // 0: none
};

struct ConnectionStatus {
  std::string connection;
  std::string topic;
  std::int32_t matched = 0;          // readers (uses) or writers (provides) matched on the topic
  std::uint64_t samples = 0;         // written (uses) or received (provides)
  std::uint64_t filtered = 0;        // provides: received but not delivered (the content filter)
  std::uint32_t deadline_missed = 0; // the connection's deadline, missed (offered or requested)
  bool in_host = false;              // both ends in one process: no DDS entities
  bool same_host = false;            // both ends on one host: a ring in shared memory
  bool relayed = false;              // a ring the node relays to and from the ends on other hosts
  bool tcp = false;                  // a TCP stream between the two ends' processes
  std::optional<AppliedQos> qos;     // as the end's transport applies it
};

// A same-host connection's ring, as the node gave it: where it is in the host's arena, and a
// reader's slot in it.
struct RingRef {
  std::uint64_t offset = 0;
  std::uint32_t slot = 0;
  bool relayed = false; // the node relays the ring to and from other hosts
};

// A QoS problem of a provides port's connection since it was last reported: the writer missed
// the deadline the connection asks for, or lost its liveliness.
struct ConnectionProblem {
  std::string connection;
  std::string problem; // "deadline missed", "liveliness lost"
  std::uint32_t count = 0;
};

// How many connections a write reached, or why one failed (the others were still written).
using WriteResult = tl::expected<std::size_t, std::string>;

// Where a provides port's callback runs.
//  ReceiveThread: on the component's receive thread, always (the default). A DDS sample wakes
//    Cyclone's receive thread, whose listener wakes the component's: two thread wake-ups.
//  Listener: a sample of a DDS connection (transport="direct", or a component process without a
//    node's shared memory) is delivered on the reader's listener, on Cyclone's receive thread,
//    saving the second wake-up (20-40 us on an idle virtual machine). DDS listeners must never
//    block, so this is the author's promise that the callback is short and never waits: no
//    sleeping, no I/O that can stall, no lock another thread holds for long, no call that waits
//    for another component. Writing to a uses port is allowed (a keep-last writer does not
//    block). The runtime keeps its own side of the promise: the callback runs there only when
//    the component is started, no other callback of the component is running and the
//    component's property lock is free (taken for the call: lock_properties() inside does not
//    wait); else the sample goes through the receive thread as with ReceiveThread. In-host and
//    same-host connections, which have no DDS listener, always use the receive thread.
enum class Delivery : std::uint8_t { ReceiveThread, Listener };

class PortBase {
public:
  PortBase(std::string name, profile::PortDirection direction, port::PortType type,
           Delivery delivery = Delivery::ReceiveThread);
  virtual ~PortBase();
  PortBase(const PortBase &) = delete;
  PortBase &operator=(const PortBase &) = delete;

  const std::string &name() const { return name_; }
  profile::PortDirection direction() const { return direction_; }
  port::PortType type() const { return type_; }
  Delivery delivery() const { return delivery_; }
  std::size_t connection_count() const;

  // For the runtime. `connect` replaces a connection of the same id. A provides port's reader
  // is attached to `loop`, which must outlive the connection. `local`: the other end is in this
  // process, and the connection bypasses DDS; `ring`: it is on this host, and the connection
  // uses that ring (`participant` is not used by either).
  Expected<void> connect(dds_entity_t participant, detail::ReceiveLoop *loop,
                         const std::string &connection, const std::string &topic,
                         const dds_qos_t *qos, std::optional<ContentFilter> filter = std::nullopt,
                         bool local = false, std::optional<RingRef> ring = std::nullopt);
  // A connection on a TCP stream (transport="tcp"): a provides port listens and returns the
  // endpoint its writer connects to; a uses port connects to `peer` within `timeout` and returns
  // "". Both ends know `token`.
  Expected<std::string> connect_tcp(detail::ReceiveLoop *loop, const std::string &connection,
                                    const dds_qos_t *qos, const std::string &peer,
                                    const std::string &token, std::chrono::milliseconds timeout);
  bool disconnect(const std::string &connection);
  void disconnect_all();
  std::vector<ConnectionStatus> status() const;
  // The peers (readers of a uses port, writers of a provides port) one connection has matched;
  // nothing when the port has no such connection.
  std::optional<std::int32_t> matched(const std::string &connection) const;
  // Provides ports: the QoS problems of each connection since the last call.
  std::vector<ConnectionProblem> take_problems();
  // Whether a connection has problems to look for: a provides port's connection with a deadline
  // or a liveliness lease.
  bool watched() const;
  // Takes what every connection received; hands it to the callback when `deliver`.
  virtual void take_all(bool deliver);
  // On a DDS listener's thread (Delivery::Listener): takes and delivers what the connection
  // received when ReceiveLoop::run_here can, else wakes the receive loop. Never blocks.
  virtual void take_here(detail::DataConnection &c);
  // On a TCP stream's thread: one frame (a record) of connection `c`, delivered there when the
  // port asked for Delivery::Listener and ReceiveLoop::run_here can, else queued for the receive
  // loop. Never waits for the port's lock.
  virtual void take_frame(detail::DataConnection &c, const std::byte *data, std::size_t bytes);
  // Returns once no callback of this port is running (one that starts later sees the caller's
  // earlier writes, e.g. a cleared delivery flag).
  void quiesce();

protected:
  // Writes `value` to every connection: its wire form to DDS, a record to each same-host ring,
  // and one shared copy (made when the port has an in-host connection) to every in-host one.
  template <typename T>
  WriteResult write_all(const T &value);

  mutable std::shared_mutex mutex_; // shared: writing, taking; exclusive: (dis)connecting
  std::map<std::string, std::unique_ptr<detail::DataConnection>> connections_;

private:
  Expected<std::unique_ptr<detail::DataConnection>>
  open_local(detail::ReceiveLoop *loop, std::unique_ptr<detail::DataConnection> c,
             const dds_qos_t *qos) const;
  Expected<std::unique_ptr<detail::DataConnection>>
  open_same_host(detail::ReceiveLoop *loop, std::unique_ptr<detail::DataConnection> c,
                 const dds_qos_t *qos, const RingRef &ring) const;

  std::string name_;
  profile::PortDirection direction_;
  port::PortType type_;
  Delivery delivery_;
};

template <typename T>
class UsesPort final : public PortBase {
public:
  explicit UsesPort(std::string name)
      : PortBase(std::move(name), profile::PortDirection::Uses, port::PortTypeOf<T>::value) {}
  // Safe from any thread. The value is serialized before write returns.
  WriteResult write(const T &value);
};

template <typename T>
class ProvidesPort final : public PortBase {
public:
  // Runs for each sample while the component is started, on the receive thread (or see
  // Delivery::Listener), one call at a time per component; `value` is valid only during the call
  // (its buffers are reused for the next sample).
  using Callback = std::function<void(const T &value)>;

  ProvidesPort(std::string name, Callback callback, Delivery delivery = Delivery::ReceiveThread)
      : PortBase(std::move(name), profile::PortDirection::Provides, port::PortTypeOf<T>::value,
                 delivery),
        callback_(std::move(callback)) {}
  void take_all(bool deliver) override;
  void take_here(detail::DataConnection &c) override;
  void take_frame(detail::DataConnection &c, const std::byte *data, std::size_t bytes) override;

private:
  void take_dds(detail::DataConnection &c, bool deliver);
  void take_local(detail::DataConnection &c, bool deliver);
  void take_same_host(detail::DataConnection &c, bool deliver);
  // Hands `value` to the callback unless the connection's filter drops it.
  void deliver(detail::DataConnection &c, const T &value);

  Callback callback_;
  T scratch_; // receives every DDS sample: its buffers grow once and are reused
};

extern template class UsesPort<port::Samples>;
extern template class UsesPort<port::PropertyEvent>;
extern template class UsesPort<port::Command>;
extern template class ProvidesPort<port::Samples>;
extern template class ProvidesPort<port::PropertyEvent>;
extern template class ProvidesPort<port::Command>;

} // namespace rsca::component
