// Private to the component runtime: connections between two components of one process (a
// component host) that bypass DDS. A writer hands each sample, copied once into an immutable
// shared value, to the inbox of every reader of the topic in the process; a reader's receive
// thread takes it from there. No serialization, no network, no copy per reader.
//
// QoS semantics kept: history (KEEP_LAST n bounds the inbox, dropping the oldest; KEEP_ALL keeps
// up to kKeepAllLimit), the requested deadline (misses counted by the reader, as DDS counts
// them), matched counts. Within one process delivery is reliable and the writer is always alive,
// so reliability and liveliness hold trivially; durability has nothing to replay because the
// domain connects before it starts the components.
#pragma once

#include <chrono>
#include <cstddef>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <tl/expected.hpp>

#include "component/port_types.hpp"

namespace rsca::component::detail {

class ReceiveLoop;

using LocalSample = std::shared_ptr<const void>; // a T of the topic's port type

// One reader's queue of samples, filled by writers' threads, drained by its receive thread.
class LocalInbox {
public:
  static constexpr std::size_t kKeepAllLimit = 65536;

  LocalInbox(ReceiveLoop &loop, std::size_t depth) : loop_(loop), depth_(depth) {}
  void push(LocalSample sample);
  std::deque<LocalSample> take();
  std::uint64_t dropped() const;
  std::uint64_t pushed() const;                // how many arrived so far
  std::size_t depth() const { return depth_; } // 0: keep all (up to kKeepAllLimit)

private:
  ReceiveLoop &loop_;
  const std::size_t depth_;
  mutable std::mutex mutex_;
  std::deque<LocalSample> queue_;
  std::uint64_t dropped_ = 0;
  std::uint64_t pushed_ = 0;
};

// The in-process side of one topic: its readers' inboxes and how many writers it has.
class LocalTopic {
public:
  explicit LocalTopic(port::PortType type) : type_(type) {}
  port::PortType type() const { return type_; }

  void add_reader(const std::shared_ptr<LocalInbox> &inbox);
  void remove_reader(const LocalInbox *inbox);
  void add_writer();
  void remove_writer();
  std::int32_t readers() const;
  std::int32_t writers() const;
  // Hands `sample` to every reader; how many there were.
  std::size_t publish(const LocalSample &sample) const;

private:
  const port::PortType type_;
  mutable std::mutex mutex_;
  std::vector<std::shared_ptr<LocalInbox>> readers_;
  std::int32_t writers_ = 0;
};

// The process's local topics by name (DDS topic names are unique per connection in a domain).
// A topic lives as long as a connection holds it.
class LocalTopics {
public:
  static LocalTopics &instance();
  // The topic of that name, made when no connection holds it; an error when it carries another
  // port type.
  tl::expected<std::shared_ptr<LocalTopic>, std::string> join(const std::string &name,
                                                              port::PortType type);

private:
  std::mutex mutex_;
  std::map<std::string, std::weak_ptr<LocalTopic>> topics_;
};

} // namespace rsca::component::detail
