// What a node daemon puts in the environment of the component processes it starts.
#pragma once

namespace rsca {

// The node daemon's pid. A component whose parent is no longer that process (the node died
// before the component asked to die with it) exits at once.
inline constexpr const char *kNodePidVariable = "RSCA_NODE_PID";

// Set to "0" when the node leaves a periodic component free to run on any of its CPUs (its GPP's
// pin_admitted_cpu is false); otherwise the process pins itself to the CPU timing admission chose.
inline constexpr const char *kPinAdmittedVariable = "RSCA_PIN_ADMITTED_CPU";

} // namespace rsca
