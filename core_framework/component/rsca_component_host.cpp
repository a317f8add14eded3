// rsca-component-host: the process a GPP starts for an application's shared-library components
// on one device (component/runtime.hpp, run_component_host).
#include "component/runtime.hpp"

int main(int argc, char **argv) {
  rsca::component::serve_forks_if_asked(argc, argv, rsca::process::kForkServerReady);
  return rsca::component::run_component_host(argc, argv);
}
