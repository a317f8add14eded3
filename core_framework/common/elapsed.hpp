// Milliseconds on the steady clock, as launch steps and benchmarks report them.
#pragma once

#include <chrono>

namespace rsca {

inline double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

} // namespace rsca
