// rsca-consumer: counts the sample sequences arriving on samples_in since start (received),
// measures the latency of each from its timestamp (last_latency_us) and logs one line every
// log_every sequences; counts the events arriving on events_in (events_received). Checks the
// order of the sequence numbers (last_sequence, sequence_gaps: sequences skipped, sequence_repeats:
// one at or before the last; last_gap_end: the sequence that ended the last gap), so that a test
// can see a sample lost, repeated or reordered.
#include <atomic>

#include "component/export.hpp"

namespace {

using rsca::component::Component;
using rsca::component::Context;
using rsca::component::Result;

class Consumer final : public Component {
public:
  explicit Consumer(const Context &context) : Component(context) {
    // Atomics: the receive thread updates and reads them without the property lock.
    property("received", received_);
    property("last_latency_us", last_latency_us_);
    property("log_every", log_every_);
    property("events_received", events_received_);
    property("last_sequence", last_sequence_);
    property("sequence_gaps", sequence_gaps_);
    property("sequence_repeats", sequence_repeats_);
    property("last_gap_end", last_gap_end_);
    provides_port<rsca::port::PropertyEvent>(
        "events_in", [this](const rsca::port::PropertyEvent &) { ++events_received_; });
    provides_port<rsca::port::Samples>(
        "samples_in", [this](const rsca::port::Samples &samples) { on_samples(samples); });
  }

private:
  Result start() override {
    received_ = 0;
    events_received_ = 0;
    sequence_gaps_ = 0;
    sequence_repeats_ = 0;
    last_gap_end_ = 0;
    return {};
  }

  void on_samples(const rsca::port::Samples &samples) {
    const std::uint64_t count = received_.fetch_add(1) + 1;
    check_order(samples.sequence, count == 1);
    const auto delay_ns = static_cast<std::int64_t>(rsca::port::now_ns() - samples.timestamp_ns);
    const double latency_us = static_cast<double>(delay_ns) / 1000.0;
    last_latency_us_.store(latency_us);
    const std::uint32_t every = log_every_.load();
    if (every != 0 && count % every == 0)
      log().info("received {} sequences; stream {} sequence {}: {} samples, latency {:.1f} us",
                 count, samples.stream_id, samples.sequence, samples.samples.size(), latency_us);
  }

  // Only the receive thread writes these; the first sequence since start has nothing before it.
  void check_order(std::uint64_t sequence, bool first) {
    const std::uint64_t last = last_sequence_.load();
    if (!first && sequence <= last)
      ++sequence_repeats_;
    else if (!first && sequence > last + 1) {
      sequence_gaps_ += sequence - last - 1;
      last_gap_end_ = sequence;
    }
    last_sequence_ = sequence;
  }

  std::atomic<std::uint64_t> received_{0};
  std::atomic<double> last_latency_us_{0.0};
  std::atomic<std::uint32_t> log_every_{0};
  std::atomic<std::uint64_t> events_received_{0};
  std::atomic<std::uint64_t> last_sequence_{0};
  std::atomic<std::uint64_t> sequence_gaps_{0};
  std::atomic<std::uint64_t> sequence_repeats_{0};
  std::atomic<std::uint64_t> last_gap_end_{0}; // the sequence received after the last gap
};

} // namespace

RSCA_COMPONENT(Consumer)
