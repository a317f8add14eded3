// DDS isolation for tests: each test process joins a DDS domain of its own, so tests running in
// parallel (and leftovers of a crashed run) never see each other.
#pragma once

#include <random>
#include <string>

#include <memory>
#include <unistd.h>

#include <catch2/catch.hpp>

#include "dds/participant.hpp"

namespace rsca::test {

// A domain id from 1 to 230 derived from the process id: ctest runs each test case in its own
// process, so concurrent tests get different ids (Cyclone maps ids above 232 to invalid ports).
inline std::uint32_t isolated_domain_id() {
  // Up to 220: with 600 participant indexes, the discovery ports of ids from 228 pass 65535.
  return 1 + static_cast<std::uint32_t>(::getpid()) % 220;
}

// A discovery tag of this test process's own: two test processes whose domain ids collide
// (or a benchmark on the same machine) still never discover each other.
inline const std::string &isolated_tag() {
  static const std::string tag = [] {
    std::random_device random;
    return "test-" + std::to_string(::getpid()) + "-" + std::to_string(random());
  }();
  return tag;
}

inline dds::DdsSettings isolated_settings() {
  auto settings = dds::DdsSettings::from_environment();
  settings.domain_id = isolated_domain_id();
  settings.tag = isolated_tag();
  return settings;
}

inline std::shared_ptr<dds::Participant> participant() {
  auto pp = dds::Participant::create(isolated_settings());
  REQUIRE(pp.has_value());
  return *pp;
}

} // namespace rsca::test
