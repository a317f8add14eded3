// The control plane's worker pool (control/worker_pool.hpp): threads started as tasks need them,
// never more than asked for, tasks run in order of arrival, and what is queued runs before stop
// returns.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <future>
#include <mutex>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>

#include "control/worker_pool.hpp"

namespace {

using rsca::control::WorkerPool;

// A gate the tasks wait at until the test opens it: holds threads busy for as long as needed.
class Gate {
public:
  void wait() {
    std::unique_lock lock(mutex_);
    ++waiting_;
    changed_.notify_all();
    changed_.wait(lock, [this] { return open_; });
  }
  // Waits until `n` tasks are at the gate; false if they are not within 10 s.
  bool reached(int n) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, std::chrono::seconds(10), [&] { return waiting_ >= n; });
  }
  void open() {
    std::lock_guard lock(mutex_);
    open_ = true;
    changed_.notify_all();
  }

private:
  std::mutex mutex_;
  std::condition_variable changed_;
  int waiting_ = 0;
  bool open_ = false;
};

} // namespace

TEST_CASE("worker pool: no thread until a task comes, one while tasks come one at a time",
          "[control][worker_pool]") {
  WorkerPool pool(4);
  CHECK(pool.threads() == 0);
  for (int i = 0; i < 20; ++i) {
    std::promise<void> done;
    pool.post([&done] { done.set_value(); });
    REQUIRE(done.get_future().wait_for(std::chrono::seconds(10)) == std::future_status::ready);
    // The next task comes once the thread is back waiting, as a caller's next call would.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (pool.idle() < pool.threads() && std::chrono::steady_clock::now() < deadline)
      std::this_thread::yield();
    REQUIRE(pool.idle() == pool.threads());
  }
  // Each task found the one thread idle once it had finished the one before.
  CHECK(pool.threads() == 1);
}

TEST_CASE("worker pool: tasks that wait together get a thread each, up to the most asked for",
          "[control][worker_pool]") {
  WorkerPool pool(3);
  Gate gate;
  std::atomic<int> ran{0};
  for (int i = 0; i < 5; ++i)
    pool.post([&] {
      gate.wait();
      ++ran;
    });
  // Three run at once (the most), the other two wait in the queue.
  REQUIRE(gate.reached(3));
  CHECK(pool.threads() == 3);
  gate.open();
  pool.stop();
  CHECK(ran == 5);
  CHECK(pool.threads() == 0);
}

TEST_CASE("worker pool: one thread runs tasks in order of arrival, stop runs what is queued and "
          "refuses what comes after",
          "[control][worker_pool]") {
  WorkerPool pool(1);
  Gate gate;
  std::vector<int> order;
  std::mutex mutex;
  pool.post([&] { gate.wait(); });
  for (int i = 0; i < 10; ++i)
    pool.post([&, i] {
      std::lock_guard lock(mutex);
      order.push_back(i);
    });
  REQUIRE(gate.reached(1));
  gate.open();
  pool.stop();
  std::vector<int> expected(10);
  for (int i = 0; i < 10; ++i)
    expected[i] = i;
  CHECK(order == expected);
  bool late = false;
  pool.post([&] { late = true; });
  pool.stop();
  CHECK_FALSE(late);
}
