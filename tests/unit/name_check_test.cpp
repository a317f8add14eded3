// When a daemon's look for a holder of its name ends (control::DiscoveryQuiet): the rule on a
// clock the test moves, so that each bound is shown to hold without waiting for it.
#include <catch2/catch.hpp>

#include "control/name_holder.hpp"

using rsca::control::DiscoveryQuiet;
using namespace std::chrono_literals;

TEST_CASE("a look for a name's holder ends once discovery is quiet, not before its least time",
          "[name_check]") {
  const auto t0 = DiscoveryQuiet::Clock::time_point{} + 1h;
  DiscoveryQuiet quiet(t0, 1000ms);
  // Nothing heard: quiet since the start, but the first exchange is given its time.
  CHECK_FALSE(quiet.over(t0 + DiscoveryQuiet::kLeast - 1ms));
  CHECK(quiet.next_look() == t0 + DiscoveryQuiet::kLeast);
  CHECK(quiet.over(t0 + DiscoveryQuiet::kLeast));
}

TEST_CASE("each discovery heard starts the quiet again", "[name_check]") {
  const auto t0 = DiscoveryQuiet::Clock::time_point{} + 1h;
  DiscoveryQuiet quiet(t0, 1000ms);
  const auto heard = t0 + 300ms;
  quiet.heard(heard);
  CHECK_FALSE(quiet.over(heard + DiscoveryQuiet::kQuiet - 1ms));
  CHECK(quiet.next_look() == heard + DiscoveryQuiet::kQuiet);
  CHECK(quiet.over(heard + DiscoveryQuiet::kQuiet));
}

TEST_CASE("a look for a name's holder never outlasts its bound, however busy discovery is",
          "[name_check]") {
  const auto t0 = DiscoveryQuiet::Clock::time_point{} + 1h;
  DiscoveryQuiet quiet(t0, 1000ms);
  for (auto t = t0; t < t0 + 1000ms; t += 50ms)
    quiet.heard(t); // never quiet for long
  CHECK_FALSE(quiet.over(t0 + 999ms));
  CHECK(quiet.next_look() == t0 + 1000ms);
  CHECK(quiet.over(t0 + 1000ms));
  // A bound shorter than the least time is the bound.
  DiscoveryQuiet brief(t0, 100ms);
  CHECK(brief.over(t0 + 100ms));
}
