// Where the GPP lets a component process run: REDHAWK's affinity directive (profile/assembly.hpp,
// ProcessorAffinity), resolved on this host (which CPUs a NUMA node or a network interface has)
// and applied to the process as it starts. The directive comes from the network: every value is
// checked, and one this host cannot honour is an error, never a silent no-op.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <sched.h>
#include <sys/types.h>

#include "common/diagnostic.hpp"
#include "protocol/node_ops.hpp"

namespace rsca::gpp {

// What the directive means here.
struct ProcessPlacement {
  std::vector<unsigned> cpus; // empty: any CPU
  std::optional<int> nice;
};

// The CPUs this process may run on (its own affinity mask): all a process it starts can have.
std::vector<unsigned> usable_cpus();

// Reads the host's CPUs, NUMA nodes and interfaces under `sys` (/sys; tests give another root);
// every CPU must be online and among `usable` (those this node may use, e.g. in its cpuset).
Expected<ProcessPlacement> resolve_affinity(const protocol::node::AffinityDirective &directive,
                                            const std::string &sys = "/sys",
                                            const std::vector<unsigned> &usable = usable_cpus());

// While it lives, the calling thread runs on `cpus` (none: unchanged), so that a process it
// starts has them from its first instruction (a child inherits its parent thread's mask); then
// the thread's own mask is back.
class ScopedThreadCpus {
public:
  explicit ScopedThreadCpus(const std::vector<unsigned> &cpus);
  ~ScopedThreadCpus();
  ScopedThreadCpus(const ScopedThreadCpus &) = delete;
  ScopedThreadCpus &operator=(const ScopedThreadCpus &) = delete;
  // Whether the mask is set (false: the kernel refused it, errno says why).
  bool pinned() const { return pinned_; }

private:
  cpu_set_t saved_{};
  bool pinned_ = false;
};

// Sets the placement's nice value on every thread of `pid` (nice cannot go back down without
// privilege, so it is set on the child, not around its start). A process already gone is no
// error: its exit is reported as any exit.
Expected<void> apply_nice(pid_t pid, const ProcessPlacement &placement);

} // namespace rsca::gpp
