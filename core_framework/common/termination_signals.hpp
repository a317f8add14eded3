// Clean shutdown on SIGINT/SIGTERM without doing work in a signal handler: the signals are
// blocked in every thread (construct this first in main, before any thread starts) and one
// thread waits for them.
#pragma once

#include <csignal>

namespace rsca {

class TerminationSignals {
public:
  TerminationSignals();
  // Blocks until SIGINT or SIGTERM arrives; returns the signal.
  int wait() const;

private:
  sigset_t set_{};
};

} // namespace rsca
