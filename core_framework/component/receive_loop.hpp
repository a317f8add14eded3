// Private to the component runtime: the one thread of a component that receives on all its
// provides ports. It waits on a waitset holding one read condition per connection, and on any
// trigger lets the component take what arrived.
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
  static Expected<std::unique_ptr<ReceiveLoop>> start(dds_entity_t participant,
                                                      std::function<void()> poll);
  ~ReceiveLoop();
  ReceiveLoop(const ReceiveLoop &) = delete;
  ReceiveLoop &operator=(const ReceiveLoop &) = delete;

  Expected<void> attach(dds_entity_t condition);
  void detach(dds_entity_t condition);
  // Stops and joins the thread; `poll` is not called afterwards. Idempotent.
  void stop();

private:
  ReceiveLoop(dds::Entity waitset, dds::Entity guard, std::function<void()> poll);
  void run();

  dds::Entity waitset_;
  dds::Entity guard_;
  std::function<void()> poll_;
  std::atomic<bool> stopping_{false};
  std::thread thread_;
};

} // namespace rsca::component::detail
