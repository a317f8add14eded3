// Private to the component runtime: the one thread of a component that receives on all its
// provides ports. Each reader's data-available listener only rings the thread's doorbell
// (shm/doorbell.hpp: never blocks); the thread then lets the component take what arrived, off
// Cyclone's own receive thread. In a process its node started, the doorbell is in the host's
// arena, where writers of same-host connections in other processes ring it too.
//
// A port whose callback its author declared short and non-blocking (Delivery::Listener) may
// instead take a DDS sample on the listener's own thread (run_here), which saves the thread
// wake-up (20-40 us on a virtual machine gone idle, docs/measurements.md) but only when nothing
// has to be waited for; else the loop takes it as for every other port. The component's callbacks
// stay one at a time, whichever thread runs them.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "common/diagnostic.hpp"
#include "dds/entity.hpp"
#include "shm/doorbell.hpp"

namespace rsca::component::detail {

class ReceiveLoop {
public:
  // Starts the thread; `poll` runs on it after every wake-up. `owner_lock`, when given, is the
  // lock the owner's callbacks may take (the component's property lock): run_here takes it
  // first, so that such a callback never waits for it on a listener's thread.
  static Expected<std::unique_ptr<ReceiveLoop>> start(std::function<void()> poll,
                                                      std::recursive_mutex *owner_lock = nullptr);
  ~ReceiveLoop();
  ReceiveLoop(const ReceiveLoop &) = delete;
  ReceiveLoop &operator=(const ReceiveLoop &) = delete;

  // Wakes the thread whenever `reader` receives data. `detach` returns once no listener call for
  // the reader is under way.
  Expected<void> attach(dds_entity_t reader);
  void detach(dds_entity_t reader);
  // Wakes the thread (never blocks): a reader received DDS data.
  void wake() const;
  // Wakes the thread (never blocks): an in-host connection delivered something.
  void wake_in_host() const;
  // Whether the owner's callbacks are to run (its component is started). The owner sets it and
  // passes it to its ports when it polls; run_here reads it.
  void set_delivering(bool delivering) { delivering_ = delivering; }
  bool delivering() const { return delivering_.load(); }
  // Runs `take` (which delivers to a callback) at once on the calling thread, a DDS listener's,
  // when that needs no wait: the owner delivers, no delivery of the owner is under way on any
  // thread (the loop's included; the callbacks stay one at a time and in order), and the owner's
  // lock is free, then held during `take`. Returns false, having run nothing, otherwise: the
  // caller then wakes the thread, which takes the data once it is free. Never blocks.
  template <typename F>
  bool run_here(F &&take);
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
  ReceiveLoop(std::function<void()> poll, std::recursive_mutex *owner_lock);
  static void on_data_available(dds_entity_t reader, void *loop);
  // Whether this thread is delivering for some loop already (a callback that wrote to DDS, whose
  // local reader's listener runs on the writer's thread): run_here then declines, since the
  // locks it would try are this thread's own.
  static bool &delivering_on_this_thread();
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
  std::atomic<bool> delivering_{false};
  std::mutex delivery_; // held by whichever thread delivers: the loop's, or a listener's
  std::recursive_mutex *owner_lock_;
  std::thread thread_;
};

template <typename F>
bool ReceiveLoop::run_here(F &&take) {
  bool &marked = delivering_on_this_thread();
  if (marked || !delivering_.load())
    return false;
  std::unique_lock one_at_a_time(delivery_, std::try_to_lock);
  if (!one_at_a_time)
    return false;
  std::unique_lock<std::recursive_mutex> owner;
  if (owner_lock_ != nullptr) {
    owner = std::unique_lock(*owner_lock_, std::try_to_lock);
    if (!owner)
      return false;
  }
  marked = true;
  struct Unmark {
    bool &flag;
    ~Unmark() { flag = false; }
  } unmark{marked};
  take();
  return true;
}

} // namespace rsca::component::detail
