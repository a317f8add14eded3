#include "component/process.hpp"

#include <sys/prctl.h>

#include <cstdlib>

#include "common/exec_environment.hpp"

namespace rsca::component::detail {

bool die_with_node() {
  const char *node = std::getenv(kNodePidVariable);
  const pid_t parent = node != nullptr ? static_cast<pid_t>(std::atol(node)) : getppid();
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  return getppid() == parent; // else the node died before the request took effect
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
