// Comparing what is reserved in two domain states, for the planner's tests.
#pragma once

#include "allocator/planner.hpp"

namespace rsca::test {

// Exact equality of what is reserved: a rejected allocation must not touch a single bit.
inline bool same_load(const allocator::DomainState &a, const allocator::DomainState &b) {
  if (a.size() != b.size())
    return false;
  for (const auto &[id, s] : a) {
    auto it = b.find(id);
    if (it == b.end() || !(it->second.load == s.load))
      return false;
  }
  return true;
}

} // namespace rsca::test
