// Checks across files, once everything a SAD or DCD references is loaded: ports against the
// SCDs, property overrides against the PRFs, external ports and properties. A value that does
// not fit its property is an error; wiring problems (ports, port types) are warnings, see
// Severity. An override of a property the PRF does not define is what REDHAWK warns about and
// ignores: it goes to `tolerated`, and a launch of a REDHAWK profile ignores the override.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "common/diagnostic.hpp"

namespace rsca::profile {

struct Connection;
struct ResolvedApplication;
struct ResolvedNode;

std::vector<Diagnostic> check_application(const ResolvedApplication &app,
                                          std::vector<Diagnostic> &tolerated);
std::vector<Diagnostic> check_node(const ResolvedNode &node, std::vector<Diagnostic> &tolerated);

// What a launch refuses of a loaded application whatever the domain holds, each located where
// it is written: first a component whose package misses a file (it explains the wiring findings
// it causes), else the wiring findings, else (for a profile written for rsca, is_strict) what
// reading it tolerated, else the connections rsca cannot make yet. The domain
// refuses them at its launch's check; `rsca launch SAD` refuses them in the user's files before
// it sends anything. Empty: a launch may begin.
std::vector<Diagnostic> launch_refusals(const ResolvedApplication &app);

// Whether the application is held to what `rsca validate --strict` holds a profile to: its SAD
// was written for rsca, not REDHAWK (no SCA DOCTYPE, XmlDocument::redhawk).
bool is_strict(const ResolvedApplication &app);

// A SAD connection's id; the plain SCA lets it be empty: connection_N then, N from 1.
std::string connection_id(const Connection &c, std::size_t index);

} // namespace rsca::profile
