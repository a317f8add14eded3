// rsca-bench-subscriber: one subscriber of the fan-out benchmark (tests/bench/port_bench.py).
// Records, per event arriving on `events_in`, the time it arrived (ns, CLOCK_MONOTONIC), by the
// event's sequence number, for sequence numbers below `capacity`; when stopped it writes them to
// `output` (0 for an event that never came; tests/bench/bench_common.hpp).
#include <atomic>

#include "../bench_common.hpp"
#include "component/runtime.hpp"

namespace {

using rsca::bench::mono_ns;
using rsca::component::Component;
using rsca::component::Context;
using rsca::component::failure;
using rsca::component::Result;
using rsca::port::PropertyEvent;

class Subscriber final : public Component {
public:
  explicit Subscriber(const Context &context) : Component(context) {
    property("capacity", capacity_);
    property("output", output_);
    property("received", received_);
    property("unexpected", unexpected_);
    provides_port<PropertyEvent>("events_in",
                                 [this](const PropertyEvent &event) { on_event(event); });
  }

private:
  Result start() override {
    if (output_.empty())
      return failure("the property output (where the receive times go) is not set");
    received_at_.assign(capacity_, 0);
    received_ = 0;
    unexpected_ = 0;
    return {};
  }

  // Port callbacks are off by now: received_at_ is this thread's.
  Result stop() override {
    if (!rsca::bench::write_u64_file(output_, received_at_))
      return failure("cannot write the receive times to " + output_);
    log().info("{} events received ({} unexpected); times in {}", received_.load(),
               unexpected_.load(), output_);
    return {};
  }

  void on_event(const PropertyEvent &event) {
    const std::uint64_t now = mono_ns();
    std::uint64_t sequence = 0;
    if (!rsca::bench::parse_event_sequence(event.value, sequence) ||
        sequence >= received_at_.size() || received_at_[sequence] != 0) {
      ++unexpected_;
      return;
    }
    received_at_[sequence] = now;
    ++received_;
  }

  std::uint32_t capacity_ = 0;
  std::string output_;
  std::atomic<std::uint64_t> received_{0};
  std::atomic<std::uint64_t> unexpected_{0};
  std::vector<std::uint64_t> received_at_; // the receive thread's while started
};

} // namespace

int main(int argc, char **argv) {
  return rsca::component::run<Subscriber>(argc, argv);
}
