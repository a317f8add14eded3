// Up to a fixed number of threads running queued tasks in order of arrival: an endpoint's request
// handlers, and the writers of its requests (so that a caller never waits on discovery). A thread
// is started when a task finds every thread busy, not before: most component processes serve a
// few calls at a time, and a launch of a hundred of them paid for three idle threads each.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace rsca::control {

class WorkerPool {
public:
  explicit WorkerPool(std::size_t threads) : most_(threads) {}
  ~WorkerPool() { stop(); }
  // Runs what is queued, then ends the threads; a task posted afterwards never runs. Idempotent.
  void stop() {
    std::vector<std::thread> threads;
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
      threads.swap(threads_);
    }
    wake_.notify_all();
    for (auto &t : threads)
      t.join();
  }
  void post(std::function<void()> task) {
    {
      std::lock_guard lock(mutex_);
      if (stopping_)
        return;
      tasks_.push_back(std::move(task));
      if (idle_ < tasks_.size() && threads_.size() < most_)
        threads_.emplace_back([this] { run(); });
    }
    wake_.notify_one();
  }
  // The threads started so far, and those of them waiting for a task.
  std::size_t threads() const {
    std::lock_guard lock(mutex_);
    return threads_.size();
  }
  std::size_t idle() const {
    std::lock_guard lock(mutex_);
    return idle_;
  }

private:
  void run() {
    for (;;) {
      std::function<void()> task;
      {
        std::unique_lock lock(mutex_);
        ++idle_;
        wake_.wait(lock, [this] { return stopping_ || !tasks_.empty(); });
        --idle_;
        if (tasks_.empty())
          return;
        task = std::move(tasks_.front());
        tasks_.pop_front();
      }
      task();
    }
  }

  const std::size_t most_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> tasks_;
  bool stopping_ = false;
  std::size_t idle_ = 0; // threads waiting for a task
  std::vector<std::thread> threads_;
};

} // namespace rsca::control
