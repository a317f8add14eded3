// The simulated robot's devices, run inside their node (node/hosted_device.hpp):
//   Robot       owns the simulated world (robot_world.hpp): the scenario as properties, the
//               run's trace and state as read-only properties, the state on its port state_out;
//   IRSensor    publishes the front range sensor's reading on range_out every period_ms;
//   DriveSystem takes velocity commands on command_in; emergency_stop takes effect at the next
//               simulation step; with no fresh command for command_timeout_ms it stops the
//               robot by itself (a controller that dies must not leave it driving).
// A DCD places Robot before the devices attached to it.
#pragma once

#include "node/logical_device.hpp"

namespace rsca::robot {

void register_robot_devices(node::DeviceRegistry &registry);

} // namespace rsca::robot
