#include "control/announcement_slots.hpp"

namespace rsca::control {

std::uint32_t AnnouncerSlots::slot_for(const std::string &address) {
  if (auto it = slots_.find(address); it != slots_.end())
    return it->second;
  std::uint32_t slot = next_;
  if (!free_.empty()) {
    slot = *free_.begin();
    free_.erase(free_.begin());
  } else {
    ++next_;
  }
  slots_.emplace(address, slot);
  return slot;
}

std::optional<std::uint32_t> AnnouncerSlots::release(const std::string &address) {
  auto it = slots_.find(address);
  if (it == slots_.end())
    return std::nullopt;
  const std::uint32_t slot = it->second;
  slots_.erase(it);
  free_.insert(slot);
  return slot;
}

std::optional<std::string> HeardSlots::heard(const std::string &announcer, std::uint32_t slot,
                                             const std::string &address) {
  const Slot at{announcer, slot};
  slot_of_[address] = at;
  auto [it, inserted] = addresses_.try_emplace(at, address);
  if (inserted || it->second == address)
    return std::nullopt;
  std::string before = std::exchange(it->second, address);
  auto where = slot_of_.find(before);
  if (where == slot_of_.end() || where->second != at)
    return std::nullopt; // heard elsewhere since
  slot_of_.erase(where);
  return before;
}

std::optional<std::string> HeardSlots::gone(const std::string &announcer, std::uint32_t slot) {
  const Slot at{announcer, slot};
  auto it = addresses_.find(at);
  if (it == addresses_.end())
    return std::nullopt;
  std::string address = std::move(it->second);
  addresses_.erase(it);
  auto where = slot_of_.find(address);
  if (where == slot_of_.end() || where->second != at)
    return std::nullopt; // heard elsewhere since
  slot_of_.erase(where);
  return address;
}

} // namespace rsca::control
