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
#include <utility>
#include <vector>

#include <tl/expected.hpp>

#include "component/component.hpp"

namespace rsca::component {

// What run returns, the process's exit status.
enum ExitStatus : int {
  kExitOk = 0,      // released, or stopped by SIGTERM/SIGINT
  kExitFailure = 1, // DDS, the endpoint or the component's constructor failed
  kExitUsage = 2,   // the exec parameters are wrong
  kExitProfile = 3, // the profile cannot be loaded or does not fit the component
};

struct ExecParams {
  std::string identifier;      // COMPONENT_IDENTIFIER (required)
  std::string name_binding;    // NAME_BINDING (the identifier when absent)
  std::string profile;         // PROFILE_NAME (required)
  std::string domain;          // DOMAIN_NAME
  std::string application;     // APPLICATION
  std::string control_address; // CONTROL_ADDRESS (required)
  std::vector<std::pair<std::string, std::string>> others; // execparam properties and the rest
  std::optional<Schedule> schedule; // RSCA_CPU, RSCA_PRIORITY, RSCA_PERIOD_NS, ... (admission)
};

// The exec parameters of argv[1..], in pairs.
tl::expected<ExecParams, std::string> parse_exec_params(int argc, const char *const *argv);

// One component of a component host (run_component_host): its exec parameters and its library.
struct HostedComponent {
  ExecParams params;
  std::filesystem::path library; // LIBRARY, as the SPD names it
};

struct HostParams {
  std::string control_address; // the host's own: it serves its components' addresses too
  std::vector<HostedComponent> components;
};

// A component host's exec parameters: CONTROL_ADDRESS <the host's>, then one group per
// component, each starting with COMPONENT_IDENTIFIER and naming its LIBRARY.
tl::expected<HostParams, std::string> parse_host_params(int argc, const char *const *argv);

using Factory = std::function<std::unique_ptr<Component>(const Context &)>;
int run_component(int argc, char **argv, const Factory &factory);

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

template <typename T>
int run(int argc, char **argv) {
  static_assert(std::is_base_of_v<Component, T>, "a component derives from Component");
  return run_component(argc, argv,
                       [](const Context &context) { return std::make_unique<T>(context); });
}

} // namespace rsca::component
