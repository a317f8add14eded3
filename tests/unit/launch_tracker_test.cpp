// The LaunchTracker: progress and cancels by launch id, a cancel that overtakes its launch, and a
// bounded memory of finished launches.
#include <string>

#include <catch2/catch.hpp>

#include "domain/launch_tracker.hpp"

using rsca::domain::LaunchStep;
using rsca::domain::LaunchTracker;

TEST_CASE("a launch's steps are its progress until it is done", "[unit][launch-tracker]") {
  LaunchTracker launches;
  REQUIRE(launches.begin("l1") != nullptr);
  launches.record("l1", {"check", "", 1.0});
  launches.record("l1", {"allocate", "2 components", 2.0});
  auto progress = launches.progress("l1");
  REQUIRE(progress.has_value());
  CHECK(progress->steps.size() == 2);
  CHECK(progress->steps[1].detail == "2 components");
  CHECK_FALSE(progress->done);
  CHECK(launches.finish("l1", true));
  CHECK(launches.progress("l1")->done);
  CHECK_FALSE(launches.progress("l2").has_value());
}

TEST_CASE("a cancel reaches a running launch, after its end it says so", "[unit][launch-tracker]") {
  LaunchTracker launches;
  auto cancelled = launches.begin("l1");
  REQUIRE(cancelled != nullptr);
  const auto outcome = launches.cancel("l1");
  CHECK(outcome.cancelled);
  CHECK(outcome.begun);
  CHECK(cancelled->load());
  // It launched all the same (the cancel came after its last step): not done, to be released.
  CHECK_FALSE(launches.finish("l1", true));
  CHECK_FALSE(launches.progress("l1")->done);
  CHECK(launches.finish("l1", false));
  CHECK(launches.progress("l1")->done);

  REQUIRE(launches.begin("l2") != nullptr);
  REQUIRE(launches.finish("l2", true));
  const auto late = launches.cancel("l2");
  CHECK_FALSE(late.cancelled);
  CHECK(late.done);
}

TEST_CASE("a cancel that overtook its launch keeps that launch from beginning",
          "[unit][launch-tracker]") {
  LaunchTracker launches;
  const auto outcome = launches.cancel("l1");
  CHECK(outcome.cancelled);
  CHECK_FALSE(outcome.done);
  CHECK_FALSE(outcome.begun);
  CHECK(launches.begin("l1") == nullptr);
  CHECK(launches.progress("l1")->done);
  // Another launch is not affected.
  CHECK(launches.begin("l2") != nullptr);
}

TEST_CASE("finished launches are forgotten beyond the last kKeptFinished, running ones never",
          "[unit][launch-tracker]") {
  LaunchTracker launches;
  REQUIRE(launches.begin("running") != nullptr);
  for (std::size_t i = 0; i < LaunchTracker::kKeptFinished + 5; ++i) {
    const std::string id = "l" + std::to_string(i);
    REQUIRE(launches.begin(id) != nullptr);
    REQUIRE(launches.finish(id, true));
  }
  // So are cancels whose launch never came.
  for (std::size_t i = 0; i < LaunchTracker::kKeptFinished + 5; ++i)
    launches.cancel("never" + std::to_string(i));
  CHECK_FALSE(launches.progress("l0").has_value());
  CHECK_FALSE(launches.progress("never0").has_value());
  CHECK(launches.progress("never" + std::to_string(LaunchTracker::kKeptFinished + 4)));
  CHECK(launches.progress("running").has_value());
}
