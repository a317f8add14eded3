#include "component/process.hpp"

#include <sys/prctl.h>

#include <cstdlib>

#include "common/exec_environment.hpp"
#include "profile/runtime_model.hpp"

namespace rsca::component::detail {

bool die_with_node() {
  const char *node = std::getenv(kNodePidVariable);
  const pid_t parent = node != nullptr ? static_cast<pid_t>(std::atol(node)) : getppid();
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  return getppid() == parent; // else the node died before the request took effect
}

tl::expected<std::vector<std::shared_ptr<const profile::ResolvedSoftPkg>>, std::string>
load_component_profiles(const std::vector<std::string> &spds, spdlog::logger &log) {
  profile::ComponentProfileLoader loader;
  std::vector<std::shared_ptr<const profile::ResolvedSoftPkg>> softpkgs;
  for (const auto &spd : spds) {
    auto softpkg = loader.load(spd);
    if (!softpkg)
      return tl::unexpected(
          fmt::format("cannot load the profile {}:\n{}", spd, softpkg.error().to_string()));
    if (!loader.fallback_reason().empty())
      log.debug("{} read from its XML: {}", spd, loader.fallback_reason());
    softpkgs.push_back(*softpkg);
  }
  return softpkgs;
}

bool wait_for_signal_or_release(const ExitEvents &events, int &signal) {
  using namespace std::chrono_literals;
  for (;;) {
    const auto event = events.wait(1s, signal);
    if (event == ExitEvents::Event::Signal)
      return true;
    if (event == ExitEvents::Event::Released)
      return false;
  }
}

} // namespace rsca::component::detail
