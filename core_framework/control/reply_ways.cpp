#include "control/reply_ways.hpp"

#include <algorithm>
#include <set>

#include <spdlog/spdlog.h>

#include "control.h" // generated from dds/control.idl

namespace rsca::control {

namespace {

dds_return_t write(dds_entity_t writer, ReplyWays::Reply &reply) {
  rsca_ctl_Reply sample{};
  sample.id = reply.id.data();
  sample.status = reply.status;
  sample.error = reply.error.data();
  sample.body = reply.body.data();
  sample.payload._buffer = reply.payload.data();
  sample.payload._length = static_cast<std::uint32_t>(reply.payload.size());
  sample.payload._maximum = sample.payload._length;
  sample.payload._release = false;
  return dds_write(writer, &sample);
}

} // namespace

ReplyWays::ReplyWays(dds_entity_t participant, dds_entity_t topic, const dds_qos_t *qos,
                     dds_entity_t waitset)
    : ways_(participant, topic, qos, kMaxWays), waitset_(waitset) {}

CallResult<void> ReplyWays::post(const std::string &caller, Reply reply) {
  auto writer = ways_.writer_for(caller);
  if (!writer)
    return tl::unexpected(writer.error());
  if (!ways_.matched_way(caller)) {
    hold(caller, *writer, std::move(reply));
    return {};
  }
  if (const dds_return_t rc = write(*writer, reply); rc < 0)
    return call_error(Status::Failed, fmt::format("reply to {}: {}", caller, dds_strretcode(rc)));
  return {};
}

void ReplyWays::hold(const std::string &caller, dds_entity_t writer, Reply reply) {
  std::optional<Held> dropped;
  {
    std::lock_guard lock(mutex_);
    if (held_.size() >= kMaxHeld) {
      dropped = std::move(held_.front());
      held_.pop_front();
    }
    held_.push_back({caller, writer, std::move(reply), Clock::now() + kWait});
  }
  // Attached twice is refused, harmlessly; a writer dropped meanwhile is detached by DDS.
  dds_waitset_attach(waitset_, writer, writer);
  if (!dropped)
    return;
  if (auto unsaid = dropped_log_.allow())
    spdlog::warn("a reply to {} dropped: {} replies wait for their callers already{}",
                 dropped->caller, kMaxHeld, LogLimiter::unsaid_note(*unsaid));
}

std::optional<ReplyWays::Clock::time_point> ReplyWays::flush(Clock::time_point now) {
  std::deque<Held> expired;
  std::set<std::string> waiting;
  std::set<dds_entity_t> done, awaited;
  std::optional<Clock::time_point> next;
  {
    std::lock_guard lock(mutex_);
    std::deque<Held> kept;
    for (auto &h : held_) {
      if (auto writer = ways_.matched_way(h.caller)) {
        if (const dds_return_t rc = write(*writer, h.reply); rc < 0)
          spdlog::warn("reply to {} failed: {}", h.caller, dds_strretcode(rc));
        done.insert(h.writer);
      } else if (h.deadline <= now) {
        done.insert(h.writer);
        expired.push_back(std::move(h));
      } else {
        waiting.insert(h.caller);
        awaited.insert(h.writer);
        next = next ? std::min(*next, h.deadline) : h.deadline;
        kept.push_back(std::move(h));
      }
    }
    held_.swap(kept);
  }
  // Left attached, a writer whose status changes again (its reader leaving) would wake the
  // receive thread at once for ever: attached only while a reply waits for its reader.
  for (const dds_entity_t writer : done)
    if (!awaited.contains(writer))
      dds_waitset_detach(waitset_, writer);
  // A way whose reader never came goes with its last reply; looked for once a second at most,
  // not at every request the receive thread takes.
  if (now - swept_ >= std::chrono::seconds(1) || !expired.empty()) {
    swept_ = now;
    ways_.drop_unmatched(now - kWait, waiting);
  }
  for (const auto &h : expired)
    if (auto unsaid = dropped_log_.allow())
      spdlog::warn("a reply to {} dropped: no reader there in {} s{}", h.caller, kWait.count(),
                   LogLimiter::unsaid_note(*unsaid));
  return next;
}

std::size_t ReplyWays::held() const {
  std::lock_guard lock(mutex_);
  return held_.size();
}

} // namespace rsca::control
