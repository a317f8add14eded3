// Private to the component runtime: the one thread of a component that receives on all its
// provides ports. Each reader's data-available listener only rings the thread's doorbell
// (shm/doorbell.hpp: never blocks); the thread then lets the component take what arrived, off
// Cyclone's own receive thread. In a process its node started, the doorbell is in the host's
// arena, where writers of same-host connections in other processes ring it too.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <thread>

#include "common/diagnostic.hpp"
#include "dds/entity.hpp"
#include "shm/doorbell.hpp"

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
  // The doorbell's offset in the host's arena, for a same-host reader's writers to ring; none
  // when the process has no arena.
  std::optional<std::uint64_t> doorbell() const { return doorbell_offset_; }
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
  std::uint32_t take_wake() const;
  std::uint32_t spin_for_wake() const;
  void sleep_until_woken(int timeout_ms) const;
  void run();

  mutable shm::Doorbell own_bell_;   // when the process has no arena
  shm::Doorbell *bell_ = &own_bell_; // own_bell_, or one in the host's arena
  std::optional<std::uint64_t> doorbell_offset_;
  dds_listener_t *listener_;
  std::function<void()> poll_;
  std::atomic<bool> stopping_{false};
  std::atomic<bool> watching_{false};
  std::thread thread_;
};

} // namespace rsca::component::detail
