// The ComponentRegistry's wait for a launch's components: done when all have registered, failed at
// once by an exit, and timed out only after a quiet interval without one more registration.
#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>

#include "domain/component_registry.hpp"

using namespace std::chrono_literals;
using rsca::control::Status;
using rsca::domain::ComponentRegistry;

namespace {

std::vector<std::string> expect_all(ComponentRegistry &registry, int count) {
  std::vector<std::string> addresses;
  for (int i = 0; i < count; ++i) {
    addresses.push_back("rsca/component/App_1/c" + std::to_string(i));
    registry.expect(addresses.back(), "node1");
  }
  return addresses;
}

} // namespace

TEST_CASE("the wait ends when every component has registered", "[unit][registry]") {
  ComponentRegistry registry;
  auto addresses = expect_all(registry, 3);
  std::thread announcer([&] {
    for (const auto &a : addresses)
      registry.announced(a);
  });
  auto ok = registry.wait_registered(addresses, 10s);
  announcer.join();
  CHECK(ok.has_value());
}

TEST_CASE("registrations that keep coming extend the wait beyond one quiet interval",
          "[unit][registry]") {
  ComponentRegistry registry;
  auto addresses = expect_all(registry, 12);
  const auto quiet = 1000ms;
  const auto began = std::chrono::steady_clock::now();
  // One registration every 150 ms: all of them take 1.8 s, longer than the quiet interval.
  std::thread announcer([&] {
    for (const auto &a : addresses) {
      std::this_thread::sleep_for(150ms); // the pace of the stimulus, not a wait for a condition
      registry.announced(a);
    }
  });
  auto ok = registry.wait_registered(addresses, quiet);
  const auto waited = std::chrono::steady_clock::now() - began;
  announcer.join();
  CHECK(ok.has_value());
  CHECK(waited > quiet);
}

TEST_CASE("a quiet interval without a registration fails and names who is missing",
          "[unit][registry]") {
  ComponentRegistry registry;
  auto addresses = expect_all(registry, 3);
  registry.announced(addresses[0]);
  auto ok = registry.wait_registered(addresses, 50ms);
  REQUIRE_FALSE(ok.has_value());
  CHECK(ok.error().status == Status::Timeout);
  CHECK_THAT(ok.error().message, Catch::Contains(addresses[1]) && Catch::Contains(addresses[2]) &&
                                     !Catch::Contains(addresses[0]));
}

TEST_CASE("an exit fails the wait at once, with the reason", "[unit][registry]") {
  ComponentRegistry registry;
  auto addresses = expect_all(registry, 2);
  std::thread reporter([&] { registry.exited(addresses[1], "exit code 3"); });
  auto ok = registry.wait_registered(addresses, 60s);
  reporter.join();
  REQUIRE_FALSE(ok.has_value());
  CHECK(ok.error().status == Status::Failed);
  CHECK_THAT(ok.error().message, Catch::Contains(addresses[1]) && Catch::Contains("exit code 3"));
}

TEST_CASE("an endpoint that disappears is waited for again, not taken for an exit",
          "[unit][registry]") {
  ComponentRegistry registry;
  auto addresses = expect_all(registry, 1);
  registry.announced(addresses[0]);
  registry.gone(addresses[0]); // its DDS lease ran out while its process lives on
  CHECK_FALSE(registry.registered(addresses[0]));
  std::thread announcer([&] { registry.announced(addresses[0]); });
  auto ok = registry.wait_registered(addresses, 10s);
  announcer.join();
  CHECK(ok.has_value());
  CHECK(registry.registered(addresses[0]));
}

TEST_CASE("a cancelled wait ends when interrupted, long before its quiet interval",
          "[unit][registry]") {
  ComponentRegistry registry;
  auto addresses = expect_all(registry, 2);
  registry.announced(addresses[0]);
  std::atomic<bool> cancelled{false};
  std::thread canceller([&] {
    cancelled = true;
    registry.interrupt();
  });
  const auto began = std::chrono::steady_clock::now();
  auto ok = registry.wait_registered(addresses, 1h, &cancelled);
  canceller.join();
  REQUIRE_FALSE(ok.has_value());
  CHECK(ok.error().status == Status::Failed);
  CHECK_THAT(ok.error().message, Catch::Contains("cancelled while 1 of 2 had registered"));
  // It ended on the interrupt, not on the hour-long quiet interval.
  CHECK(std::chrono::steady_clock::now() - began < 1h);
}

TEST_CASE("a wait cancelled before it began still counts who had registered", "[unit][registry]") {
  // The interrupt may come before the wait's first look (CI saw "0 of 2" here).
  ComponentRegistry registry;
  auto addresses = expect_all(registry, 2);
  registry.announced(addresses[0]);
  std::atomic<bool> cancelled{true};
  auto ok = registry.wait_registered(addresses, 1h, &cancelled);
  REQUIRE_FALSE(ok.has_value());
  CHECK_THAT(ok.error().message, Catch::Contains("cancelled while 1 of 2 had registered"));
}

TEST_CASE("an interrupt without a cancellation leaves a wait waiting", "[unit][registry]") {
  ComponentRegistry registry;
  auto addresses = expect_all(registry, 1);
  std::atomic<bool> cancelled{false};
  std::thread other([&] {
    registry.interrupt(); // another launch's cancel
    registry.announced(addresses[0]);
  });
  auto ok = registry.wait_registered(addresses, 10s, &cancelled);
  other.join();
  CHECK(ok.has_value());
}
