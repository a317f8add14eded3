// The ways from one endpoint to others over one control topic (requests, or replies): a DDS
// writer per partition, that is per address, made on first use and kept while an endpoint reads
// there. A daemon answers a stream of short-lived callers (every CLI command is a process with an
// address of its own), so a way whose readers have all left is dropped when the next one is made:
// the daemon holds writers for the endpoints alive and not one per caller it ever had (issue 18,
// defect 5: 10-13 KB per CLI command, never given back).
//
// A CLI client's address is the exception: all of them share one way, a writer in the wildcard
// partition that matches every CLI address (protocol::cli_clients_partition), kept for good.
// Cyclone keeps each endpoint's discovery instance after the endpoint is deleted (~370 B), so a
// writer per command would still grow the daemon for ever. A reply there reaches every CLI reading
// at the time; each takes only the replies to its own calls (by id).
//
// "Left" is DDS's own word for it: the writer was matched and is matched no longer, because the
// endpoint there exited, withdrew its reader, or lost its participant's lease. The endpoint asks
// the same question of the calls it has sent (departed()), so that a caller whose addressee died
// learns it then, not at its deadline.
#pragma once

#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>

#include "control/endpoint.hpp"
#include "dds/entity.hpp"

namespace rsca::control {

class PartitionWriters {
public:
  using Clock = std::chrono::steady_clock;

  // Writers of `topic` with QoS `qos` (copied), under publishers of `participant`. At most
  // `max_ways` (0: no bound): to make one more, the least recently used is dropped.
  PartitionWriters(dds_entity_t participant, dds_entity_t topic, const dds_qos_t *qos,
                   std::size_t max_ways = 0);

  // The writer into `partition` (the shared one for a CLI client's), made when there is none yet
  // (and then the ways whose readers left are dropped). BadRequest for a partition with
  // wildcards: a caller cannot have its replies sent to everyone.
  CallResult<dds_entity_t> writer_for(const std::string &partition);
  // The same, once a reader in that partition is matched (in a shared way: a reader whose own
  // partition is `partition`): volatile data written before the
  // match would be lost. Unavailable at `deadline`, or as soon as `stopping` is set.
  CallResult<dds_entity_t> matched_writer(const std::string &partition, Clock::time_point deadline,
                                          const std::atomic<bool> &stopping);
  void erase(const std::string &partition);
  // The writer into `partition` if there is one already and the reader there is matched (as
  // matched_writer says it); nothing else, and never a new way. It counts as a use.
  std::optional<dds_entity_t> matched_way(const std::string &partition);
  // Drops the ways never matched and not used since `unused_since` (a caller that never read its
  // replies), but those in `kept`; how many went.
  std::size_t drop_unmatched(Clock::time_point unused_since, const std::set<std::string> &kept);

  // The partitions whose writer was matched and is matched no longer.
  std::set<std::string> departed() const;
  std::size_t size() const;

private:
  struct Way {
    dds::Entity publisher; // carries the partition
    dds::Entity writer;
    bool shared = false; // the CLI clients' way: never dropped
    Clock::time_point used = Clock::now();
  };

  // Drops the ways whose readers left, then, at the bound, the least recently used. Called with
  // mutex_ held, before a way is made.
  void make_room_locked();

  dds_entity_t participant_;
  dds_entity_t topic_;
  dds::Qos qos_;
  std::size_t max_ways_;
  mutable std::mutex mutex_;
  std::map<std::string, Way> ways_;
};

} // namespace rsca::control
