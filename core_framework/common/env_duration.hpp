// A duration in microseconds from an environment variable, read once by the caller (the spin
// times of the components' receive loops and of the node's relay): unset, empty, not a whole
// number or negative gives `fallback`.
#pragma once

#include <chrono>
#include <cstdlib>

namespace rsca {

inline std::chrono::microseconds microseconds_from_env(const char *name,
                                                       std::chrono::microseconds fallback) {
  const char *text = std::getenv(name);
  if (text == nullptr || *text == '\0')
    return fallback;
  char *end = nullptr;
  const long value = std::strtol(text, &end, 10);
  return *end == '\0' && value >= 0 ? std::chrono::microseconds{value} : fallback;
}

} // namespace rsca
