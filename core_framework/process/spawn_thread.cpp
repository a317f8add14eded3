#include "process/spawn_thread.hpp"

namespace rsca::process {

SpawnThread::SpawnThread() : thread_([this](const std::stop_token &stop) { loop(stop); }) {}

SpawnThread::~SpawnThread() {
  thread_.request_stop();
  wake_.notify_all();
}

void SpawnThread::post(std::function<void()> task) {
  {
    std::lock_guard lock(mutex_);
    tasks_.push(std::move(task));
  }
  wake_.notify_one();
}

void SpawnThread::loop(const std::stop_token &stop) {
  std::unique_lock lock(mutex_);
  for (;;) {
    wake_.wait(lock, stop, [this] { return !tasks_.empty(); });
    if (tasks_.empty())
      return; // stop requested, nothing left to run
    auto task = std::move(tasks_.front());
    tasks_.pop();
    lock.unlock();
    task();
    lock.lock();
  }
}

} // namespace rsca::process
