// rsca-stop-crash: the RSCA paper's controller. For every range reading it commands the drive:
// forward at `speed` while the reading is at or above `threshold`, then a stop, latched. Each
// command carries the time its reading was taken (timestamp_ns), so the drive can measure the
// sensor-to-command latency through the middleware.
#include "component/export.hpp"

namespace {

using rsca::component::Component;
using rsca::component::Context;
using rsca::component::Result;

class StopCrash final : public Component {
public:
  explicit StopCrash(const Context &context)
      : Component(context), commands_(uses_port<rsca::port::Command>("command_out")) {
    // on_range is short and never waits (atomics, one write to a keep-last port): it runs on
    // DDS's receive thread when it can, and the command leaves a thread wake-up sooner.
    provides_port<rsca::port::Samples>(
        "range_in", [this](const rsca::port::Samples &s) { on_range(s); },
        rsca::component::Delivery::Listener);
    property("threshold", threshold_);
    property("speed", speed_);
    property("stopped", stopped_);
    property("stop_range", stop_range_);
    property("commands_sent", commands_sent_);
  }

private:
  Result start() override {
    stopped_ = false;
    return {};
  }

  void on_range(const rsca::port::Samples &reading) {
    if (reading.samples.empty())
      return;
    const double range = reading.samples.front();
    if (!stopped_.load() && range < threshold_.load()) {
      stopped_ = true;
      stop_range_ = range;
      log().info("range {:.3f} m below {:.3f} m: stopping", range, threshold_.load());
    }
    command_.timestamp_ns = reading.timestamp_ns;
    command_.name = "velocity";
    command_.args = {stopped_.load() ? 0.0 : speed_.load(), 0.0};
    if (commands_.write(command_))
      ++commands_sent_;
    ++command_.sequence;
  }

  rsca::component::UsesPort<rsca::port::Command> &commands_;
  rsca::port::Command command_{0, 0, context().name, "velocity", {}, ""};
  // Read on the receive thread, written by configure: atomics (component/component.hpp).
  std::atomic<double> threshold_{0.6};
  std::atomic<double> speed_{0.3};
  std::atomic<bool> stopped_{false};
  std::atomic<double> stop_range_{0.0};
  std::atomic<std::uint64_t> commands_sent_{0};
};

} // namespace

RSCA_COMPONENT(StopCrash)
