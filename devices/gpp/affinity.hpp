// Where the GPP lets a component process run: REDHAWK's affinity directive (profile/assembly.hpp,
// ProcessorAffinity), resolved on this host (which CPUs a NUMA node or a network interface has)
// and applied to the process as it starts. The directive comes from the network: every value is
// checked, and one this host cannot honour is an error, never a silent no-op.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <sys/types.h>

#include "common/diagnostic.hpp"
#include "protocol/node_ops.hpp"

namespace rsca::gpp {

// What the directive means here.
struct ProcessPlacement {
  std::vector<unsigned> cpus; // empty: any CPU
  std::optional<int> nice;
};

// Reads the host's CPUs, NUMA nodes and interfaces under `sys` (/sys; tests give another root).
Expected<ProcessPlacement> resolve_affinity(const protocol::node::AffinityDirective &directive,
                                            const std::string &sys = "/sys");

// Pins every thread of `pid` to the placement's CPUs and sets its nice value.
Expected<void> apply_placement(pid_t pid, const ProcessPlacement &placement);

} // namespace rsca::gpp
