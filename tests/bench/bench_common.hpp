// What the port benchmarks' components (tests/bench/components) and their raw-DDS twins
// (tests/bench/raw/raw_dds.cpp) share, so that both sides send the same bytes, stamp them with the
// same clock and hand their measurements to tests/bench/port_bench.py in the same form.
//
// - Time: CLOCK_MONOTONIC in nanoseconds. Every process of one host reads the same monotonic
//   clock, and it never steps, so a receive time minus a send time taken in two processes is a
//   latency. (The benchmark samples carry it in timestamp_ns, which elsewhere holds
//   CLOCK_REALTIME: these samples never leave the benchmark.)
// - Payloads of 64 bytes serialized (XCDR1, without the 4-byte encapsulation header):
//   a SampleSeq with an empty stream id and 3 doubles (ping-pong), a PropertyEvent with an empty
//   source, id "e" and a 35-character value {"sequence":N} padded with blanks (fan-out).
//   `rsca-bench-raw sizes` prints what Cyclone really serializes.
// - Results: a file of little-endian uint64 values, nothing else (port_bench.py reads it with
//   array('Q')): round-trip times for the pinger, send times per sequence number for a
//   publisher, receive times per sequence number (0: never received) for a subscriber.
#pragma once

#include <time.h>

#include <charconv>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

namespace rsca::bench {

inline std::uint64_t mono_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1'000'000'000u +
         static_cast<std::uint64_t>(ts.tv_nsec);
}

// Ping-pong sample: 3 doubles.
inline constexpr std::size_t kSampleDoubles = 3;

// Fan-out event: id and value of fixed sizes, so every event is the same 64 bytes.
inline constexpr std::string_view kEventId = "e";
inline constexpr std::size_t kEventValueLength = 35;
inline constexpr std::string_view kEventPrefix = "{\"sequence\":";

// {"sequence":N} padded with blanks to kEventValueLength characters (valid JSON).
inline void format_event_value(std::uint64_t sequence, std::string &out) {
  out.assign(kEventPrefix);
  char digits[24];
  const auto end = std::to_chars(digits, digits + sizeof digits, sequence).ptr;
  out.append(digits, end);
  out.push_back('}');
  if (out.size() < kEventValueLength)
    out.append(kEventValueLength - out.size(), ' ');
}

// The N of a value format_event_value made, or false.
inline bool parse_event_sequence(std::string_view value, std::uint64_t &sequence) {
  if (!value.starts_with(kEventPrefix))
    return false;
  value.remove_prefix(kEventPrefix.size());
  return std::from_chars(value.data(), value.data() + value.size(), sequence).ec == std::errc();
}

// Writes `values` to `path` as raw little-endian uint64 (x86_64 is little-endian).
inline bool write_u64_file(const std::string &path, const std::vector<std::uint64_t> &values) {
  std::FILE *f = std::fopen(path.c_str(), "wb");
  if (f == nullptr)
    return false;
  const bool ok =
      std::fwrite(values.data(), sizeof(std::uint64_t), values.size(), f) == values.size();
  return std::fclose(f) == 0 && ok;
}

// The paced publication of the fan-out benchmark, the same for the component and for raw DDS.
// Phases run one after the other: `count` events at `rate_hz` each, with `gap_ms` of silence
// before a phase (its backlog drains). Sequence numbers run on across phases from 0.
struct Phase {
  std::uint64_t count = 0;
  double rate_hz = 0;
  std::uint64_t gap_ms = 0;
};

// How far a run of the schedule has got: call `due` with the time now; it says how many events
// to send now (paced at the phase's rate, in bursts when called less often than the period) and
// how long the caller may sleep before asking again.
class Pacer {
public:
  explicit Pacer(std::vector<Phase> phases) : phases_(std::move(phases)) {
    for (const auto &p : phases_)
      total_ += p.count;
  }

  std::uint64_t total() const { return total_; }
  bool finished() const { return phase_ >= phases_.size(); }
  std::size_t phase() const { return phase_; }

  struct Due {
    std::uint64_t send = 0;     // events to send now
    std::uint64_t sleep_ns = 0; // until the next call
    bool overran = false;       // the phase ran over twice its planned time: it was cut short
  };

  // `now` in CLOCK_MONOTONIC ns. Call `sent(n)` after sending.
  Due due(std::uint64_t now) {
    Due d;
    while (phase_ < phases_.size()) {
      const Phase &p = phases_[phase_];
      if (phase_start_ == 0)
        phase_start_ = now + p.gap_ms * 1'000'000u;
      if (now < phase_start_) {
        d.sleep_ns = phase_start_ - now;
        return d;
      }
      const double period_ns = p.rate_hz > 0 ? 1e9 / p.rate_hz : 0;
      const auto elapsed = static_cast<double>(now - phase_start_);
      std::uint64_t should =
          p.rate_hz > 0 ? static_cast<std::uint64_t>(elapsed / period_ns) + 1 : p.count;
      if (should > p.count)
        should = p.count;
      if (sent_in_phase_ >= p.count) {
        next_phase();
        continue;
      }
      // A phase that cannot keep its rate is cut short (its remaining events are never sent)
      // once it has taken twice its planned time: the later, faster phases would only be worse.
      if (p.rate_hz > 0 && elapsed > 2 * period_ns * static_cast<double>(p.count) + 100e6) {
        d.overran = true;
        skipped_ += p.count - sent_in_phase_;
        phases_.resize(phase_ + 1);
        next_phase();
        return d;
      }
      d.send = should - sent_in_phase_;
      const double next_at = period_ns * static_cast<double>(should);
      d.sleep_ns = next_at > elapsed ? static_cast<std::uint64_t>(next_at - elapsed) : 0;
      if (d.sleep_ns < kMinSleepNs)
        d.sleep_ns = kMinSleepNs; // above 10 kHz events leave in small bursts
      return d;
    }
    return d;
  }

  void sent(std::uint64_t n) { sent_in_phase_ += n; }
  std::uint64_t skipped() const { return skipped_; }

private:
  static constexpr std::uint64_t kMinSleepNs = 100'000;

  void next_phase() {
    ++phase_;
    phase_start_ = 0;
    sent_in_phase_ = 0;
  }

  std::vector<Phase> phases_;
  std::uint64_t total_ = 0;
  std::size_t phase_ = 0;
  std::uint64_t phase_start_ = 0;
  std::uint64_t sent_in_phase_ = 0;
  std::uint64_t skipped_ = 0;
};

} // namespace rsca::bench
