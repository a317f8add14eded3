// Lists of CPUs or NUMA nodes as Linux writes them ("0-3,6", as in /sys/devices/system/cpu/online
// and REDHAWK's affinity values): read by the profile reader, which checks an affinity's value,
// and by the node, which pins a process to them.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <tl/expected.hpp>

namespace rsca {

// The highest CPU or node number a list may name: far above any robot computer, it bounds what
// a profile (untrusted input) can make a node allocate, and a cpu_set_t holds it (CPU_SETSIZE).
inline constexpr unsigned kMaxCpuIndex = 1023;

// The numbers of `text` in increasing order without repeats; "" and malformed text are errors.
tl::expected<std::vector<unsigned>, std::string> parse_cpu_list(std::string_view text);

} // namespace rsca
