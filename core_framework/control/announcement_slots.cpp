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
  auto [it, inserted] = addresses_.try_emplace({announcer, slot}, address);
  if (inserted || it->second == address)
    return std::nullopt;
  std::string before = std::move(it->second);
  it->second = address;
  return before;
}

std::optional<std::string> HeardSlots::gone(const std::string &announcer, std::uint32_t slot) {
  auto it = addresses_.find({announcer, slot});
  if (it == addresses_.end())
    return std::nullopt;
  std::string address = std::move(it->second);
  addresses_.erase(it);
  return address;
}

} // namespace rsca::control
