// A thread of its own to start processes from, that lives as long as what it started should.
//
// Linux delivers a child's PR_SET_PDEATHSIG (a component process asks for SIGKILL when its node
// dies: component/process.cpp) when the *thread* that forked it exits, not the process. A node
// that starts processes from the threads serving its requests would have them killed whenever one
// of those threads ends — at shutdown, before the GPP's ordered stop (SIGINT, SIGTERM, then
// SIGKILL) could run. Whoever owns the processes owns one SpawnThread, destroyed after it has
// stopped them, and starts each of them with run().
#pragma once

#include <condition_variable>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <queue>
#include <thread>
#include <type_traits>

namespace rsca::process {

class SpawnThread {
public:
  SpawnThread();
  ~SpawnThread(); // runs what was queued, then ends the thread
  SpawnThread(const SpawnThread &) = delete;
  SpawnThread &operator=(const SpawnThread &) = delete;

  // Runs `task` on the thread and returns its result (or rethrows what it threw). Whatever the
  // child should inherit from its parent thread (a CPU mask, a nice value) is set inside `task`.
  // A task that calls run() itself runs inline (it would otherwise wait for itself).
  template <typename Task>
  std::invoke_result_t<Task> run(Task &&task) {
    if (std::this_thread::get_id() == thread_.get_id())
      return std::forward<Task>(task)();
    // The task is the posted function's own: the caller may wake and go before it returns.
    auto packaged = std::make_shared<std::packaged_task<std::invoke_result_t<Task>()>>(
        std::forward<Task>(task));
    auto result = packaged->get_future();
    post([packaged] { (*packaged)(); });
    return result.get();
  }

private:
  void post(std::function<void()> task);
  void loop(const std::stop_token &stop);

  std::mutex mutex_;
  std::condition_variable_any wake_;
  std::queue<std::function<void()>> tasks_;
  std::jthread thread_; // last: started once the rest exists
};

} // namespace rsca::process
