// rsca-bench-ping: the pinging half of the port-latency benchmark (tests/bench/port_bench.py).
// Strict ping-pong: it writes a 64-byte sample on `out` and writes the next one only when the echo
// of the last has come back on `in`, from the receive callback itself (no thread hand-off). The
// first `warmup` round trips are not recorded, the next `count` are; then it writes their times
// (ns, CLOCK_MONOTONIC, tests/bench/bench_common.hpp) to `output` and sets `done`.
//
// A ping whose echo has not come back after `timeout_ms` is sent again (counted in `resent`): the
// first ones may be written before the echo's reader is matched, and a volatile writer does not
// keep them for it. An echo of an earlier attempt is recognized by its timestamp and ignored.
#include <algorithm>
#include <atomic>
#include <mutex>

#include "../bench_common.hpp"
#include "component/runtime.hpp"

namespace {

using rsca::bench::mono_ns;
using rsca::component::Clock;
using rsca::component::Component;
using rsca::component::Context;
using rsca::component::failure;
using rsca::component::Result;
using rsca::port::Samples;

class Ping final : public Component {
public:
  explicit Ping(const Context &context) : Component(context), out_(uses_port<Samples>("out")) {
    property("count", count_);
    property("warmup", warmup_);
    property("timeout_ms", timeout_ms_);
    property("output", output_);
    property("completed", completed_);
    property("resent", resent_);
    property("done", done_);
    provides_port<Samples>("in", [this](const Samples &echo) { on_echo(echo); });
    ping_.samples.assign(rsca::bench::kSampleDoubles, 0.0);
  }

private:
  Result start() override {
    if (output_.empty())
      return failure("the property output (where the round-trip times go) is not set");
    std::lock_guard lock(mutex_);
    warmup_now_ = warmup_;
    target_ = std::uint64_t{warmup_} + count_;
    timeout_ns_ = std::uint64_t{timeout_ms_} * 1'000'000u;
    rtts_.clear();
    rtts_.reserve(count_);
    ping_.sequence = 0;
    sent_at_ = 0;
    completed_ = 0;
    resent_ = 0;
    finished_ = false;
    done_ = false;
    return {};
  }

  // On the service thread: sends the first ping, sends again a ping whose echo is overdue, and
  // writes the results once the callback has done the last round trip.
  std::optional<Clock::duration> service() override {
    if (finished_.load()) {
      std::lock_guard lock(mutex_);
      if (!rsca::bench::write_u64_file(output_, rtts_))
        log().error("cannot write the round-trip times to {}", output_);
      log().info("{} round trips done ({} resent); times in {}", rtts_.size(), resent_.load(),
                 output_);
      done_ = true;
      return std::nullopt;
    }
    std::lock_guard lock(mutex_);
    const std::uint64_t now = mono_ns();
    if (sent_at_ == 0 || now - sent_at_ > timeout_ns_) {
      if (sent_at_ != 0)
        ++resent_;
      send(now);
    }
    // Back when the ping in flight would be overdue (10 ms at the soonest): like the raw ping's
    // loop, it does not wake while echoes come back in time. The end is seen within a timeout.
    const std::uint64_t overdue_in = sent_at_ + timeout_ns_ - std::min(now, sent_at_ + timeout_ns_);
    return std::chrono::nanoseconds(std::max<std::uint64_t>(overdue_in, 10'000'000u));
  }

  void on_echo(const Samples &echo) {
    const std::uint64_t now = mono_ns();
    std::lock_guard lock(mutex_);
    if (finished_.load() || echo.sequence != ping_.sequence ||
        echo.timestamp_ns != ping_.timestamp_ns)
      return; // a late echo of a ping that was sent again
    const std::uint64_t completed = completed_.fetch_add(1) + 1;
    if (completed > warmup_now_)
      rtts_.push_back(now - sent_at_);
    if (completed >= target_) {
      finished_ = true;
      return;
    }
    ++ping_.sequence;
    send(mono_ns());
  }

  // With mutex_ held.
  void send(std::uint64_t now) {
    sent_at_ = now;
    ping_.timestamp_ns = now;
    if (auto written = out_.write(ping_); !written)
      log().warn("{}", written.error());
  }

  rsca::component::UsesPort<Samples> &out_;
  std::uint32_t count_ = 10000;
  std::uint32_t warmup_ = 100;
  std::uint32_t timeout_ms_ = 200;
  std::string output_;
  std::atomic<std::uint64_t> completed_{0};
  std::atomic<std::uint64_t> resent_{0};
  std::atomic<bool> done_{false};

  std::mutex mutex_; // the ping in flight: the receive callback and the service thread
  Samples ping_;
  std::uint64_t sent_at_ = 0;
  std::uint64_t warmup_now_ = 0;
  std::uint64_t target_ = 0;
  std::uint64_t timeout_ns_ = 0;
  std::vector<std::uint64_t> rtts_;
  std::atomic<bool> finished_{false};
};

} // namespace

int main(int argc, char **argv) {
  return rsca::component::run<Ping>(argc, argv);
}
