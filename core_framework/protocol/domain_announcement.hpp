// What a domain daemon announces of itself on the announcement topic, at its own address.
#pragma once

#include <cstdint>
#include <string>

#include "protocol/codec.hpp"

namespace rsca::protocol::domain {

// What a domain daemon announces of itself at its address (kind "domain"): who serves the domain,
// so that a second daemon of the same name on the same DDS domain and tag can say who holds it
// (control/name_holder.hpp) instead of serving beside it.
struct DomainAnnouncement {
  std::string domain;
  std::int64_t pid = 0;
  std::string host;
  std::uint64_t incarnation = 0;
  static constexpr auto fields() {
    using R = DomainAnnouncement;
    return std::tuple{required("domain", &R::domain), required("pid", &R::pid),
                      required("host", &R::host), required("incarnation", &R::incarnation)};
  }
};
inline constexpr const char *kDomainKind = "domain";

} // namespace rsca::protocol::domain
