// HostMonitor: a device that publishes its host's CPU load and free memory as events on its uses
// port status_out, every period_ms. What a robot's supervisor listens to; also the simplest
// device with a port, so the domain's device connections are exercised without a robot.
#pragma once

#include "node/logical_device.hpp"

namespace rsca::monitor {

void register_host_monitor(node::DeviceRegistry &registry);

} // namespace rsca::monitor
