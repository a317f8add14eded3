// What a node daemon puts in the environment of the component processes it starts.
#pragma once

namespace rsca {

// The node daemon's pid. A component whose parent is no longer that process (the node died
// before the component asked to die with it) exits at once.
inline constexpr const char *kNodePidVariable = "RSCA_NODE_PID";

} // namespace rsca
