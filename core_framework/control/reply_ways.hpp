// An endpoint's replies on their way to their callers (issue 37, defect 4). A reply goes out at
// once when its caller's reader is matched; otherwise it is held here, not on the handler thread
// that made it, until the reader comes or its time is up. A handler thread never waits for a
// caller: 160 requests naming a reply address nobody reads held every one of the domain's
// workers for 5 s each, and `rsca ls apps` failed meanwhile.
//
// Bounded: at most kMaxHeld replies held (the oldest dropped to make room), at most kMaxWays ways
// (PartitionWriters drops the least recently used to make one more), and a way whose reader never
// came is dropped once nothing is held for it, so that addresses nobody reads leave nothing behind.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/log_limiter.hpp"
#include "control/partition_writers.hpp"

namespace rsca::control {

class ReplyWays {
public:
  using Clock = std::chrono::steady_clock;
  static constexpr std::size_t kMaxWays = 256;
  static constexpr std::size_t kMaxHeld = 1024;
  // How long a reply waits for its caller's reader: a caller's reader is there before it sends,
  // so this is discovery's time to match, with room to spare.
  static constexpr std::chrono::seconds kWait{5};

  // A reply, owning its parts (control.idl's Reply).
  struct Reply {
    std::string id;
    std::int32_t status = 0;
    std::string error;
    std::string body;
    std::vector<std::uint8_t> payload;
  };

  // Writers of `topic` (the reply topic) under `participant`; a writer with a reply held is
  // attached to `waitset`, which wakes when its reader comes (then call flush()).
  ReplyWays(dds_entity_t participant, dds_entity_t topic, const dds_qos_t *qos,
            dds_entity_t waitset);

  // Sends `reply` to `caller` now, or holds it (see above). An error only when there can be no
  // way to `caller` (a pattern, or DDS refused a writer).
  CallResult<void> post(const std::string &caller, Reply reply);
  // Writes the held replies whose reader came, drops those whose time is up and the ways nobody
  // came to; the next time something held is due, if anything is. The receive thread calls it.
  std::optional<Clock::time_point> flush(Clock::time_point now = Clock::now());

  // The way to `caller`, made ahead of its first reply.
  CallResult<dds_entity_t> prepare(const std::string &caller) { return ways_.writer_for(caller); }
  void erase(const std::string &caller) { ways_.erase(caller); }
  std::size_t ways() const { return ways_.size(); }
  std::size_t held() const;

private:
  struct Held {
    std::string caller;
    dds_entity_t writer;
    Reply reply;
    Clock::time_point deadline;
  };

  void hold(const std::string &caller, dds_entity_t writer, Reply reply);

  PartitionWriters ways_;
  dds_entity_t waitset_;
  mutable std::mutex mutex_; // guards held_
  std::deque<Held> held_;    // oldest first
  Clock::time_point swept_;  // when flush last dropped the ways nobody came to
  LogLimiter dropped_log_;
};

} // namespace rsca::control
