// One name, one holder: a daemon about to serve an address (a domain's, a node's) first looks on
// its DDS domain and tag for a live announcement of that address by another run. Without it, a
// namesake served beside the holder: the same partition (both took its requests), the same
// announcement instance (the namesake's stop disposed the holder's, and the domain dropped a live
// node with its processes running on: issue 39).
//
// A namesake and a restart are told apart by whether the holder lives. A run that was killed has
// no participant any more, and Cyclone keeps no durable data apart from its writers (transient-
// local history is served by the writer that wrote it): its announcement, still alive in the
// caches of those who had it until its lease ends, never reaches a newcomer, so a node killed and
// started again at once finds no holder (shown by domain_node_failure_test's restart within a
// 60 s lease). A holder found but whose pid no longer runs its program on this host (it died
// during the look) is not one either (may_still_run).
//
// The look is bounded (kNameCheck): a holder whose announcement has not reached this process by
// then (DDS discovery slower than that) is missed, and two namesakes started at the same moment
// both go on. It is a guard against an operator's mistake, not a lock.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "dds/participant.hpp"
#include "protocol/codec.hpp"

namespace rsca::control {

// Discovery of the other participants and their durable announcements takes tens of milliseconds
// on one host or a LAN; a second leaves room for a loaded host.
inline constexpr std::chrono::milliseconds kNameCheck{1000};

// When a look for a holder may end before its bound: once discovery has gone quiet. A holder's
// announcement comes in a burst of discovery (its participant, then its writer matching ours, then
// its durable samples), which starts as soon as both participants exist: Cyclone answers a new
// participant's announcement at once. So the look ends when nothing new (participant, match,
// sample) has been heard for `quiet`, and not before `least` has passed (the first exchange), nor
// after the bound. Without it every daemon start waited the whole second (issue 39's cost in CI:
// ~1 s on each of several hundred test domains).
class DiscoveryQuiet {
public:
  static constexpr std::chrono::milliseconds kLeast{250};
  static constexpr std::chrono::milliseconds kQuiet{150};

  using Clock = std::chrono::steady_clock;
  DiscoveryQuiet(Clock::time_point start, std::chrono::milliseconds bound)
      : earliest_(start + std::min(bound, std::chrono::milliseconds(kLeast))),
        deadline_(start + bound), last_heard_(start) {}

  // Something was discovered at `now`: the quiet starts again.
  void heard(Clock::time_point now) { last_heard_ = now; }
  // The moment to look again if nothing is heard before; the look is over from then on.
  Clock::time_point next_look() const {
    return std::min(deadline_, std::max(earliest_, last_heard_ + kQuiet));
  }
  bool over(Clock::time_point now) const { return now >= next_look(); }

private:
  Clock::time_point earliest_;
  Clock::time_point deadline_;
  Clock::time_point last_heard_;
};

// The body of a live announcement of `address` (alive, not withdrawn), as soon as one arrives;
// nothing when none did before discovery went quiet (DiscoveryQuiet) or `wait` passed.
std::optional<nlohmann::json> live_announcement(const dds::Participant &participant,
                                                const std::string &address,
                                                std::chrono::milliseconds wait);

// Whether the run of `program` that announced itself as `pid` on `host` may still be running. An
// announcement outlives its announcer by its DDS lease when the announcer is killed, so a live
// announcement alone does not tell a namesake from a run that just died and is being restarted.
// On this host the pid does: a run that died has no process of its pid running `program` (a pid
// reused by another program is not it; a zombie runs nothing). On another host nothing here can
// look, and a run moves host only with its operator: it is taken to run.
bool may_still_run(const std::string &host, std::int64_t pid, const std::string &program);

// The name the kernel gives the program this process runs (its first 15 bytes).
std::string own_program();

// "<what> is served by pid P on host H (DDS domain D, tag T)" when that run of `program` may
// still run (may_still_run); nothing, said in the log, when it is gone.
std::optional<std::string> held_by(const dds::Participant &participant, const std::string &what,
                                   const std::string &host, std::int64_t pid,
                                   const std::string &program);

// Who holds `address`, if a live run of `program` (rsca-domaind, rsca-noded) does: "<what> is
// served by pid P on host H (DDS domain D, tag T)". `Announcement` is the holder's announcement
// type (it has `pid` and `host`); a body that does not decode is another version's or another
// kind's, named as such.
template <typename Announcement>
std::optional<std::string> live_holder(const dds::Participant &participant,
                                       const std::string &address, const std::string &what,
                                       const std::string &program) {
  const auto body = live_announcement(participant, address, kNameCheck);
  if (!body)
    return std::nullopt;
  const auto &dds = participant.settings();
  const auto where = fmt::format("DDS domain {}, tag \"{}\"", dds.domain_id, dds.tag);
  auto holder = protocol::decode<Announcement>(*body);
  if (!holder)
    return fmt::format("{} is announced at {} on {} by a process that does not say who it is ({})",
                       what, address, where, holder.error());
  return held_by(participant, what, holder->host, holder->pid, program);
}

} // namespace rsca::control
