// The process around a component: what `main` of a component executable calls.
//
//   int main(int argc, char **argv) { return rsca::component::run<MyComponent>(argc, argv); }
//
// run parses the exec parameters (docs/architecture.md, "Component protocol"), loads the SPD
// named by PROFILE_NAME with its PRF and SCD, constructs the component, checks its property
// bindings against the PRF and its ports against the SCD, applies the PRF defaults and the
// execparams, joins DDS (RSCA_DDS_* environment), opens the control endpoint at CONTROL_ADDRESS,
// serves the component.* operations and announces itself (kind "component"). It returns after
// component.release, SIGTERM or SIGINT, once the component is stopped and released and its DDS
// entities are gone.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <tl/expected.hpp>

#include "component/component.hpp"
#include "process/fork_request.hpp"
#include "protocol/exec_params.hpp"

namespace rsca::component {

// What run returns, the process's exit status.
enum ExitStatus : int {
  kExitOk = 0,      // released, or stopped by SIGTERM/SIGINT
  kExitFailure = 1, // DDS, the endpoint or the component's constructor failed
  kExitUsage = 2,   // the exec parameters are wrong
  kExitProfile = 3, // the profile cannot be loaded or does not fit the component
};

// The exec parameters (protocol/exec_params.hpp: made by the ApplicationFactory, read here).
using protocol::ExecParams;
using protocol::HostParams;
using protocol::parse_exec_params;
using protocol::parse_host_params;

using Factory = std::function<std::unique_ptr<Component>(const Context &)>;
// Runs the component its node started; with `--rsca-describe FILE` only, writes what its code
// declares to FILE instead (profile/code_description.hpp) and exits.
int run_component(int argc, char **argv, const Factory &factory);
inline constexpr std::string_view kDescribeOption = "--rsca-describe";

// A shared-library component exports this function (component/export.hpp): it hands out the
// component's factory.
inline constexpr const char *kFactorySymbol = "rsca_component_factory";
using FactoryExport = void (*)(Factory *out);

// The component host (rsca-component-host): one process serving several shared-library
// components of one application on one device, on one DDS participant. Its exec parameters are
// those of each component in turn, each group starting with COMPONENT_IDENTIFIER and naming its
// library with LIBRARY <path> (relative: to the SPD's folder, else the host's own lib folder).
// It serves every component at its own control address, exactly as a component process would,
// and returns once all of them are released, or on SIGTERM or SIGINT.
int run_component_host(int argc, char **argv);

// What the main of a component executable calls first (component/export.hpp's does): started by
// its node as a fork server, it serves the node until the node lets it go, and returns only in a
// process it forked, with that process's arguments (process/fork_service.hpp). Otherwise it
// returns at once. `ready` is process::kForkServerReady, passed from main so that its bytes are in
// the executable, where the node looks for them before it starts one as a fork server. Code that
// main runs before this call runs once, in the fork server; no thread may have started.
void serve_forks_if_asked(int &argc, char **&argv, std::string_view ready);

template <typename T>
int run(int argc, char **argv) {
  static_assert(std::is_base_of_v<Component, T>, "a component derives from Component");
  return run_component(argc, argv,
                       [](const Context &context) { return std::make_unique<T>(context); });
}

} // namespace rsca::component
