#include "common/process_priority.hpp"

#include <sys/resource.h>

#include <atomic>
#include <cerrno>

namespace rsca {

namespace {

// The nice value the process was started with: what the processes it starts get.
std::atomic<int> g_application_nice{0};

int current_nice() {
  errno = 0;
  const int nice = ::getpriority(PRIO_PROCESS, 0);
  return errno == 0 ? nice : 0;
}

} // namespace

int run_above_applications(int nice) {
  g_application_nice = current_nice();
  if (nice < g_application_nice)
    ::setpriority(PRIO_PROCESS, 0, nice); // refused without the right to: stays as it was
  return current_nice();
}

int application_nice() {
  return g_application_nice;
}

ApplicationPriority::ApplicationPriority() : saved_(current_nice()) {
  if (saved_ < g_application_nice)
    ::setpriority(PRIO_PROCESS, 0, g_application_nice);
}

ApplicationPriority::~ApplicationPriority() {
  if (saved_ < g_application_nice)
    ::setpriority(PRIO_PROCESS, 0, saved_);
}

} // namespace rsca
