// The receive loop of a component (component/receive_loop.hpp): a wake runs the owner's poll on
// the loop's thread; while watching, the loop also polls on its own, and not otherwise.
#include <atomic>
#include <chrono>
#include <memory>
#include <thread>

#include <catch2/catch.hpp>

#include "component/receive_loop.hpp"

using namespace std::chrono_literals;
using rsca::component::detail::ReceiveLoop;

namespace {

bool eventually(const std::atomic<int> &polls, int at_least) {
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  while (polls.load() < at_least) {
    if (std::chrono::steady_clock::now() > deadline)
      return false;
    std::this_thread::sleep_for(5ms); // pacing the poll of a condition
  }
  return true;
}

} // namespace

TEST_CASE("a wake runs the poll on the loop's thread", "[unit][receive-loop]") {
  std::atomic<int> polls{0};
  std::atomic<bool> other_thread{false};
  const auto caller = std::this_thread::get_id();
  auto loop = ReceiveLoop::start([&] {
    other_thread = std::this_thread::get_id() != caller;
    ++polls;
  });
  REQUIRE(loop.has_value());
  (*loop)->wake_in_host();
  CHECK(eventually(polls, 1));
  CHECK(other_thread);
}

TEST_CASE("a watching loop polls on its own, once it stops watching it waits for a wake",
          "[unit][receive-loop]") {
  std::atomic<int> polls{0};
  auto loop = ReceiveLoop::start([&] { ++polls; });
  REQUIRE(loop.has_value());
  (*loop)->set_watching(true);
  CHECK(eventually(polls, 4)); // the wake of set_watching, then every 100 ms with nothing sent
  const int watched = polls.load();
  (*loop)->set_watching(false);
  // set_watching's own wake (or a poll already under way; the wake then comes within the window)
  CHECK(eventually(polls, watched + 1));
  const int idle_from = polls.load();
  std::this_thread::sleep_for(350ms); // the window watched: three wake intervals and more
  CHECK(polls.load() - idle_from <= 1);
  const int before_wake = polls.load();
  (*loop)->wake_in_host();
  CHECK(eventually(polls, before_wake + 1));
}
