// Announcement slots: the instance keys of the announcement topic.
//
// An announcement is keyed by its announcer and a slot number, not by the address it announces.
// A node announces every process it serves; were the key the process's address, each launch would
// make new instances, and Cyclone (0.10) keeps every instance a transient-local writer ever wrote,
// disposed and unregistered ones included (about 330 B each: the soak of issue 18). A slot is
// reused once its address is withdrawn, so a writer's instances are bounded by the most addresses
// it announced at one time.
//
// AnnouncerSlots is the writer's side (which slot an address has); HeardSlots the reader's (which
// address a slot held, so that a slot disposed or left without writers says which address went).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>

namespace rsca::control {

class AnnouncerSlots {
public:
  // The slot of `address`: the one it has, or the lowest free one.
  std::uint32_t slot_for(const std::string &address);
  // Frees the slot of `address` and returns it; nothing if it had none.
  std::optional<std::uint32_t> release(const std::string &address);
  bool has(const std::string &address) const { return slots_.contains(address); }
  std::size_t size() const { return slots_.size(); }

private:
  std::map<std::string, std::uint32_t> slots_;
  std::set<std::uint32_t> free_;
  std::uint32_t next_ = 0;
};

class HeardSlots {
public:
  // A slot now holds `address`; returns the address it held before, if another that was not
  // heard in another slot since.
  std::optional<std::string> heard(const std::string &announcer, std::uint32_t slot,
                                   const std::string &address);
  // A slot was disposed or lost its writer; returns the address it held, if any was heard.
  std::optional<std::string> gone(const std::string &announcer, std::uint32_t slot);
  std::size_t size() const { return addresses_.size(); }

private:
  using Slot = std::pair<std::string, std::uint32_t>; // announcer, slot
  std::map<Slot, std::string> addresses_;
  // Where each address was heard last: a take returns samples by instance, not in time order, so
  // an address withdrawn and announced again in another slot may be heard there before its old
  // slot's end, which then must not end it.
  std::map<std::string, Slot> slot_of_;
};

} // namespace rsca::control
