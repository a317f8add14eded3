// rsca-bench-publisher: the publishing side of the fan-out benchmark (tests/bench/port_bench.py).
// Once its writer on `events_out` has matched `subscribers` readers, it publishes 64-byte events
// (tests/bench/bench_common.hpp) by a schedule: `warmup` events then `latency_count` events at
// `latency_rate_hz` (for the latency), then one step of `step_ms` per rate of `step_rates_hz`,
// each after `gap_ms` of silence (for the sustained rate). Each event carries its sequence number;
// the send time of each (ns, CLOCK_MONOTONIC) goes to `output` at the end, then `done` is set.
#include <atomic>

#include "../bench_common.hpp"
#include "component/runtime.hpp"

namespace {

using rsca::bench::mono_ns;
using rsca::component::Clock;
using rsca::component::Component;
using rsca::component::Context;
using rsca::component::failure;
using rsca::component::Result;
using rsca::port::PropertyEvent;

class Publisher final : public Component {
public:
  explicit Publisher(const Context &context)
      : Component(context), out_(uses_port<PropertyEvent>("events_out")) {
    property("subscribers", subscribers_);
    property("match_timeout_ms", match_timeout_ms_);
    property("warmup", warmup_);
    property("latency_count", latency_count_);
    property("latency_rate_hz", latency_rate_hz_);
    property("step_rates_hz", step_rates_hz_);
    property("step_ms", step_ms_);
    property("gap_ms", gap_ms_);
    property("output", output_);
    property("matched", matched_);
    property("sent", sent_);
    property("failed_writes", failed_writes_);
    property("skipped", skipped_);
    property("done", done_);
    event_.id = rsca::bench::kEventId;
  }

private:
  Result start() override {
    if (output_.empty())
      return failure("the property output (where the send times go) is not set");
    std::vector<rsca::bench::Phase> phases{{warmup_, latency_rate_hz_, 0},
                                           {latency_count_, latency_rate_hz_, 0}};
    for (double rate : step_rates_hz_)
      phases.push_back({static_cast<std::uint64_t>(rate * step_ms_ / 1000.0 + 0.5), rate, gap_ms_});
    pacer_.emplace(std::move(phases));
    send_ns_.assign(pacer_->total(), 0);
    sequence_ = 0;
    started_at_ = mono_ns();
    publishing_ = false;
    matched_ = 0;
    sent_ = 0;
    failed_writes_ = 0;
    skipped_ = 0;
    done_ = false;
    return {};
  }

  std::optional<Clock::duration> service() override {
    const std::uint64_t now = mono_ns();
    if (!publishing_) {
      std::int32_t matched = 0;
      for (const auto &c : out_.status())
        matched += c.matched;
      matched_ = matched;
      if (matched < static_cast<std::int32_t>(subscribers_)) {
        if (now - started_at_ < std::uint64_t{match_timeout_ms_} * 1'000'000u)
          return std::chrono::milliseconds(5);
        log().error("only {} of {} subscribers matched after {} ms: publishing anyway", matched,
                    subscribers_, match_timeout_ms_);
      }
      publishing_ = true;
      log().info("{} subscribers matched: publishing {} events", matched, pacer_->total());
    }
    const auto due = pacer_->due(now);
    if (due.overran)
      log().warn("a step could not keep its rate: cut short, the later steps are skipped");
    for (std::uint64_t i = 0; i < due.send; ++i)
      send();
    pacer_->sent(due.send);
    if (pacer_->finished()) {
      skipped_ = pacer_->skipped();
      if (!rsca::bench::write_u64_file(output_, send_ns_))
        log().error("cannot write the send times to {}", output_);
      log().info("{} events sent, {} failed, {} skipped; send times in {}", sent_.load(),
                 failed_writes_.load(), skipped_.load(), output_);
      done_ = true;
      return std::nullopt;
    }
    return std::chrono::nanoseconds(due.sleep_ns);
  }

  void send() {
    rsca::bench::format_event_value(sequence_, event_.value);
    const std::uint64_t now = mono_ns();
    event_.timestamp_ns = now;
    if (auto written = out_.write(event_); written && *written > 0) {
      send_ns_[sequence_] = now;
      ++sent_;
    } else if (failed_writes_++ % 1000 == 0) {
      log().warn("event {} not written: {}", sequence_,
                 written ? std::string("no connection") : written.error());
    }
    ++sequence_;
  }

  rsca::component::UsesPort<PropertyEvent> &out_;
  std::uint32_t subscribers_ = 1;
  std::uint32_t match_timeout_ms_ = 30000;
  std::uint32_t warmup_ = 100;
  std::uint32_t latency_count_ = 1000;
  double latency_rate_hz_ = 100;
  std::vector<double> step_rates_hz_;
  std::uint32_t step_ms_ = 1000;
  std::uint32_t gap_ms_ = 300;
  std::string output_;
  std::atomic<std::int32_t> matched_{0};
  std::atomic<std::uint64_t> sent_{0};
  std::atomic<std::uint64_t> failed_writes_{0};
  std::atomic<std::uint64_t> skipped_{0};
  std::atomic<bool> done_{false};

  // The service thread's own (the property lock is held around service()).
  std::optional<rsca::bench::Pacer> pacer_;
  std::vector<std::uint64_t> send_ns_;
  std::uint64_t sequence_ = 0;
  std::uint64_t started_at_ = 0;
  bool publishing_ = false;
  PropertyEvent event_;
};

} // namespace

int main(int argc, char **argv) {
  return rsca::component::run<Publisher>(argc, argv);
}
