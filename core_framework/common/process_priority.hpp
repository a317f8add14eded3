// Daemons run above the applications they serve: a node daemon that loses the CPU to busy
// components for longer than its DDS lease (1 s) is taken for dead by the domain, which then
// tears down every application on it. The processes a node starts run at the priority the node
// was started with. Nice values are per thread on Linux, and a new thread or process inherits
// its creator's.
#pragma once

namespace rsca {

// The nice value of the daemons: above every application at nice 0 (and below real-time ones).
inline constexpr int kDaemonNice = -10;

// The calling thread, and every thread it starts from now on, at `nice`, if the process may raise
// its priority (root or CAP_SYS_NICE); returns the nice value it runs at. First in main, before
// any thread exists.
int run_above_applications(int nice = kDaemonNice);

// The nice value the process was started with, which the processes it starts get.
int application_nice();

// For its scope, the calling thread at the nice value its process was started with (before
// run_above_applications), so that a process it starts runs as an application would; then back
// (or left there if the process may no longer raise it).
class ApplicationPriority {
public:
  ApplicationPriority();
  ~ApplicationPriority();
  ApplicationPriority(const ApplicationPriority &) = delete;
  ApplicationPriority &operator=(const ApplicationPriority &) = delete;

private:
  int saved_;
};

} // namespace rsca
