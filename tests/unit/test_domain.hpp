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

// A domain id derived from the process id: ctest runs each test case in its own process, so
// concurrent tests mostly get different ids, and the discovery tag below separates those that
// do not. At most dds::kLastPortSafeDomainId, or any socket another process opens may take the
// domain's discovery port first and the domain cannot be created ("address in use").
inline std::uint32_t isolated_domain_id() {
  return 1 + static_cast<std::uint32_t>(::getpid()) % dds::kLastPortSafeDomainId;
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
