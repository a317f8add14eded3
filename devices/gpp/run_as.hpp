// Whom the GPP runs component processes as: its run_as property (GPP.prf.xml), which a DCD may
// set. Until the control plane is authenticated, anyone who can reach a node can have it launch
// a package: what runs is then at most an unprivileged user's, not root's.
#pragma once

#include <optional>
#include <string>

#include "common/diagnostic.hpp"
#include "node/logical_device.hpp"
#include "process/credentials.hpp"

namespace rsca::gpp {

// The default: the system user the Debian package's postinst creates; where a host has none,
// kFallbackRunAs, said in the node's log.
inline constexpr const char *kDefaultRunAs = "rsca";
inline constexpr const char *kFallbackRunAs = "nobody";

// The credentials the device's component processes (and the fork servers they are forked from)
// take; none: the node's own, where the DCD sets run_as to root, or where the node is not root
// and so cannot change user. An error for a DCD run_as that is not a user of this host. Logs
// what it decided and why.
Expected<std::optional<process::Credentials>> component_user(const node::DeviceContext &context);

} // namespace rsca::gpp
