#include "sim/ode_handles.hpp"

namespace rsca::sim::ode {

namespace {

struct Runtime {
  // dInitODE2 also allocates the data of the thread that calls it.
  Runtime() { dInitODE2(0); }
  ~Runtime() { dCloseODE(); }
  Runtime(const Runtime &) = delete;
  Runtime &operator=(const Runtime &) = delete;
};

} // namespace

void ensure_ready_on_this_thread() {
  // A function-local static: initialised once, thread-safely, and torn down after every World
  // (which calls this in its constructor, so is constructed after it).
  static const Runtime runtime;
  thread_local const bool thread_ready = dAllocateODEDataForThread(dAllocateMaskAll) != 0;
  (void)runtime;
  (void)thread_ready;
}

} // namespace rsca::sim::ode
