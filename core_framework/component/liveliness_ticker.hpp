// Private to the component runtime: what a DDS participant's lease thread does for its writers,
// for same-host writers (shm/ring.hpp) whose connection asks for automatic liveliness with a
// lease. One thread per process, and only while there are such writers: every third of the
// shortest lease it says each is alive. A process that is frozen (stopped, hung in the kernel)
// stops saying it, and its readers see liveliness lost.
#pragma once

#include <chrono>
#include <condition_variable>
#include <map>
#include <mutex>
#include <thread>

#include "shm/ring.hpp"

namespace rsca::component::detail {

class LivelinessTicker {
public:
  static LivelinessTicker &instance();
  ~LivelinessTicker();

  // `writer` must stay until remove().
  void add(shm::RingWriter *writer, std::chrono::nanoseconds lease);
  void remove(shm::RingWriter *writer);

private:
  LivelinessTicker() = default;
  void run();

  std::mutex mutex_;
  std::condition_variable changed_;
  std::map<shm::RingWriter *, std::chrono::nanoseconds> writers_;
  bool stopping_ = false;
  std::thread thread_;
};

} // namespace rsca::component::detail
