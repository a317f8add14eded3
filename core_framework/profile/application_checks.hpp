// Checks across files, once everything a SAD or DCD references is loaded: ports against the
// SCDs, property overrides against the PRFs, external ports and properties. Property problems
// are errors; wiring problems (ports, port types) are warnings, see Severity.
#pragma once

#include <vector>

#include "common/diagnostic.hpp"

namespace rsca::profile {

struct ResolvedApplication;
struct ResolvedNode;

std::vector<Diagnostic> check_application(const ResolvedApplication &app);
std::vector<Diagnostic> check_node(const ResolvedNode &node);

} // namespace rsca::profile
