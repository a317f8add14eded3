#include "monitor/host_monitor.hpp"

#include <fmt/format.h>

#include "component/component.hpp"
#include "gpp/host_info.hpp"
#include "node/device_export.hpp"
#include "node/hosted_device.hpp"

namespace rsca::monitor {
namespace {

using component::Clock;

class HostMonitor final : public component::Component {
public:
  explicit HostMonitor(const component::Context &context)
      : Component(context), out_(uses_port<port::PropertyEvent>("status_out")) {
    property("period_ms", period_ms_);
    property("reports", reports_);
  }

private:
  std::optional<Clock::duration> service() override {
    const auto load = sampler_.sample();
    const auto meminfo = gpp::read_proc_file("/proc/meminfo");
    const auto memory = meminfo ? gpp::parse_meminfo(*meminfo) : gpp::parse_meminfo("");
    event_.timestamp_ns = port::now_ns();
    event_.value =
        fmt::format(R"({{"sequence": {}, "cpu_load": {}, "memory_available_mb": {}}})", reports_,
                    load.value_or(0.0), memory ? memory->available_bytes >> 20 : 0);
    if (out_.write(event_))
      ++reports_;
    return std::chrono::milliseconds(std::max<std::uint32_t>(period_ms_, 1));
  }

  component::UsesPort<port::PropertyEvent> &out_;
  port::PropertyEvent event_{0, context().name, "host_status", ""};
  gpp::CpuLoadSampler sampler_;
  std::uint32_t period_ms_ = 100;
  std::uint64_t reports_ = 0;
};

} // namespace

void register_host_monitor(node::DeviceRegistry &registry) {
  registry.add("HostMonitor", node::hosted_device<HostMonitor>());
}

} // namespace rsca::monitor

RSCA_DEVICES(rsca::monitor::register_host_monitor)
