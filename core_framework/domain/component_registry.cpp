#include "domain/component_registry.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace rsca::domain {

void ComponentRegistry::expect(const std::string &address, const std::string &node) {
  std::lock_guard lock(mutex_);
  Entry entry;
  entry.node = node;
  entries_[address] = std::move(entry);
}

std::vector<std::string> ComponentRegistry::node_gone(const std::string &node,
                                                      const std::string &why) {
  std::vector<std::string> gone;
  {
    std::lock_guard lock(mutex_);
    for (auto &[address, e] : entries_) {
      if (e.node != node || e.exited)
        continue;
      e.exited = true;
      e.why = why;
      gone.push_back(address);
    }
  }
  changed_.notify_all();
  return gone;
}

void ComponentRegistry::reachable_again(const std::string &address) {
  {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(address);
    if (it == entries_.end())
      return;
    it->second.exited = false;
    it->second.why.clear();
    it->second.registered = true;
  }
  changed_.notify_all();
}

void ComponentRegistry::announced(const std::string &address) {
  {
    std::lock_guard lock(mutex_);
    auto &e = entries_[address];
    e.registered = true;
  }
  changed_.notify_all();
}

// Not an exit: under load a participant's DDS lease can run out while its process lives on, and
// its endpoint comes back with its next announcement. Exits come from the node (exited) or with
// the node itself (node_gone).
void ComponentRegistry::gone(const std::string &address) {
  {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(address);
    if (it == entries_.end())
      return;
    it->second.registered = false;
  }
  changed_.notify_all();
}

void ComponentRegistry::exited(const std::string &address, const std::string &why) {
  {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(address);
    if (it == entries_.end() || it->second.exited)
      return;
    it->second.exited = true;
    it->second.why = why;
  }
  changed_.notify_all();
}

void ComponentRegistry::forget(const std::string &address) {
  std::lock_guard lock(mutex_);
  entries_.erase(address);
}

bool ComponentRegistry::registered(const std::string &address) const {
  std::lock_guard lock(mutex_);
  auto it = entries_.find(address);
  return it != entries_.end() && it->second.registered && !it->second.exited;
}

control::CallResult<void>
ComponentRegistry::wait_registered(const std::vector<std::string> &addresses,
                                   std::chrono::milliseconds quiet,
                                   const std::atomic<bool> *cancelled) {
  std::unique_lock lock(mutex_);
  std::string failure;
  std::size_t registered = 0;
  // Counts the registered addresses; false as soon as one has exited or the wait is cancelled.
  auto count = [&] {
    registered = 0;
    for (const auto &a : addresses) {
      auto it = entries_.find(a);
      if (it != entries_.end() && it->second.exited) {
        failure = fmt::format("{} exited before registering, on node {}: {}", a, it->second.node,
                              it->second.why);
        return false;
      }
      registered += it != entries_.end() && it->second.registered ? 1 : 0;
    }
    // Checked after counting so that the message gives the count at the moment of cancelling.
    if (cancelled != nullptr && cancelled->load()) {
      failure =
          fmt::format("cancelled while {} of {} had registered", registered, addresses.size());
      return false;
    }
    return true;
  };
  while (count() && registered < addresses.size()) {
    const std::size_t before = registered;
    const bool progressed = changed_.wait_for(lock, quiet, [&] {
      return !count() || registered == addresses.size() || registered > before;
    });
    if (!progressed)
      return control::call_error(control::Status::Timeout,
                                 fmt::format("not registered in time ({} ms without one more): {}",
                                             quiet.count(), fmt::join(missing(addresses), ", ")));
  }
  if (!failure.empty())
    return control::call_error(control::Status::Failed, failure);
  return {};
}

void ComponentRegistry::interrupt() {
  { std::lock_guard lock(mutex_); }
  changed_.notify_all();
}

std::vector<std::string>
ComponentRegistry::missing(const std::vector<std::string> &addresses) const {
  std::vector<std::string> out;
  for (const auto &a : addresses)
    if (auto it = entries_.find(a); it == entries_.end() || !it->second.registered)
      out.push_back(a);
  return out;
}

bool ComponentRegistry::wait_gone(const std::string &address,
                                  std::chrono::steady_clock::time_point deadline) {
  std::unique_lock lock(mutex_);
  return changed_.wait_until(lock, deadline, [&] {
    auto it = entries_.find(address);
    return it == entries_.end() || it->second.exited;
  });
}

} // namespace rsca::domain
