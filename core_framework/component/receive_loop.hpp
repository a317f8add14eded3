// Private to the component runtime: the one thread of a component that receives on all its
// provides ports. Each reader's data-available listener only wakes the thread (a flag, and a futex
// wake only when the thread sleeps: never blocks); the thread then lets the component take what
// arrived, off Cyclone's own receive thread.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <thread>

#include "common/diagnostic.hpp"
#include "dds/entity.hpp"

namespace rsca::component::detail {

class ReceiveLoop {
public:
  // Starts the thread; `poll` runs on it after every wake-up.
  static Expected<std::unique_ptr<ReceiveLoop>> start(std::function<void()> poll);
  ~ReceiveLoop();
  ReceiveLoop(const ReceiveLoop &) = delete;
  ReceiveLoop &operator=(const ReceiveLoop &) = delete;

  // Wakes the thread whenever `reader` receives data. `detach` returns once no listener call for
  // the reader is under way.
  Expected<void> attach(dds_entity_t reader);
  void detach(dds_entity_t reader);
  // Wakes the thread (never blocks): an in-host connection delivered something.
  void wake_in_host() const;
  // Stops and joins the thread; `poll` is not called afterwards. Idempotent.
  void stop();
  // With `watching`, the thread also wakes every 100 ms when nothing arrives, for its owner to
  // look for connection problems; without, it sleeps until data comes.
  void set_watching(bool watching);
  // Its thread, for its owner to name and place.
  std::thread &thread() { return thread_; }

private:
  explicit ReceiveLoop(std::function<void()> poll);
  static void on_data_available(dds_entity_t reader, void *loop);
  void wake() const;
  bool take_wake() const;
  bool spin_for_wake() const;
  void sleep_until_woken(int timeout_ms) const;
  void run();

  mutable std::atomic<std::uint32_t> woken_{0};    // something arrived (or stop)
  mutable std::atomic<std::uint32_t> sleeping_{0}; // the thread waits on woken_
  dds_listener_t *listener_;
  std::function<void()> poll_;
  std::atomic<bool> stopping_{false};
  mutable std::atomic<bool> in_host_data_{false};
  std::atomic<bool> watching_{false};
  std::thread thread_;
};

} // namespace rsca::component::detail
