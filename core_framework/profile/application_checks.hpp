// Checks across files, once everything a SAD or DCD references is loaded: ports against the
// SCDs, property overrides against the PRFs, external ports and properties. A value that does
// not fit its property is an error; wiring problems (ports, port types) are warnings, see
// Severity. An override of a property the PRF does not define is what REDHAWK warns about and
// ignores: it goes to `tolerated`, and a launch ignores the override.
#pragma once

#include <vector>

#include "common/diagnostic.hpp"

namespace rsca::profile {

struct ResolvedApplication;
struct ResolvedNode;

std::vector<Diagnostic> check_application(const ResolvedApplication &app,
                                          std::vector<Diagnostic> &tolerated);
std::vector<Diagnostic> check_node(const ResolvedNode &node, std::vector<Diagnostic> &tolerated);

} // namespace rsca::profile
