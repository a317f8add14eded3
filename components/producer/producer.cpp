// rsca-producer: publishes sample sequences on samples_out at rate_hz, each of payload_size
// samples of a 10 Hz sine at the stream's sample_rate, stamped with the time of publication; and
// with each one an event "tick" {"sequence": n} on events_out (for event channels); last_sequence
// is the sequence number last published.
#include <atomic>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "component/export.hpp"

namespace {

using rsca::component::Clock;
using rsca::component::Component;
using rsca::component::Context;
using rsca::component::Result;

struct Stream {
  std::string stream_id;
  double sample_rate = 0;
};

class Producer final : public Component {
public:
  explicit Producer(const Context &context)
      : Component(context), out_(uses_port<rsca::port::Samples>("samples_out")),
        events_(uses_port<rsca::port::PropertyEvent>("events_out")) {
    property("rate_hz", rate_hz_);
    property("payload_size", payload_size_);
    property("message", message_);
    property("last_sequence", last_sequence_);
    struct_property("stream", stream_,
                    {{"stream_id", &Stream::stream_id}, {"sample_rate", &Stream::sample_rate}});
  }

private:
  static constexpr double kToneHz = 10.0;

  Result start() override {
    log().info("{}: publishing {} samples at {} Hz on stream {}", message_, payload_size_, rate_hz_,
               stream_.stream_id);
    return {};
  }

  std::optional<Clock::duration> service() override {
    fill();
    if (auto written = out_.write(samples_); !written && failures_++ % 100 == 0)
      log().warn("{} (failures so far: {})", written.error(), failures_);
    tick_.timestamp_ns = samples_.timestamp_ns;
    tick_.value = fmt::format(R"({{"sequence": {}}})", samples_.sequence);
    if (auto written = events_.write(tick_); !written && failures_++ % 100 == 0)
      log().warn("{} (failures so far: {})", written.error(), failures_);
    last_sequence_ = samples_.sequence;
    ++samples_.sequence;
    return std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(1.0 / rate_hz_));
  }

  // The next sequence, in the buffers of the last (no allocation unless payload_size grew).
  void fill() {
    samples_.stream_id = stream_.stream_id;
    samples_.sample_rate = stream_.sample_rate;
    samples_.samples.resize(payload_size_);
    const double first = static_cast<double>(samples_.sequence) * payload_size_;
    const double step = stream_.sample_rate > 0 ? 1.0 / stream_.sample_rate : 0.0;
    for (std::size_t i = 0; i < samples_.samples.size(); ++i)
      samples_.samples[i] =
          std::sin(2 * std::numbers::pi * kToneHz * (first + static_cast<double>(i)) * step);
    samples_.timestamp_ns = rsca::port::now_ns();
  }

  rsca::component::UsesPort<rsca::port::Samples> &out_;
  rsca::component::UsesPort<rsca::port::PropertyEvent> &events_;
  rsca::port::PropertyEvent tick_{0, context().name, "tick", ""};
  double rate_hz_ = 100.0;
  std::uint32_t payload_size_ = 64;
  std::string message_;
  Stream stream_;
  rsca::port::Samples samples_;
  std::uint64_t failures_ = 0;
  std::atomic<std::uint64_t> last_sequence_{0}; // read by queries while service() writes
};

} // namespace

RSCA_COMPONENT(Producer)
