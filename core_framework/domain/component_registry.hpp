// Which component processes have registered (announced themselves) and which have exited, so
// that a launch can wait for its components — bounded, and failing at once when one dies.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "control/endpoint.hpp"

namespace rsca::domain {

class ComponentRegistry {
public:
  // A launch is about to start a component at this address: from now on its registration and
  // exit count. Exits of addresses nobody expects (released components) are ignored.
  void expect(const std::string &address, const std::string &node);
  void announced(const std::string &address);
  // Its endpoint disappeared from DDS: not registered until it announces itself again.
  void gone(const std::string &address);
  void exited(const std::string &address, const std::string &why);
  // The node is lost: marks its components exited for the launches that wait on them (they
  // cannot be reached), and returns their addresses.
  std::vector<std::string> node_gone(const std::string &node, const std::string &why);
  // Its node is back and its process lived on: registered again, no longer exited.
  void reachable_again(const std::string &address);
  // Forgets an address (its component was released), so a later one can reuse it.
  void forget(const std::string &address);

  bool registered(const std::string &address) const;

  // Waits until every address has registered; fails at once when one of them exits or when
  // `cancelled` (if given) is set and interrupt() called, or when `quiet` passes without one more
  // of them registering, naming which did not. The wait is bounded by progress, not by a total:
  // a hundred processes on a busy host register one after another for longer than any one of
  // them may take (docs/architecture.md on discovery cost), yet a stuck launch still ends.
  control::CallResult<void> wait_registered(const std::vector<std::string> &addresses,
                                            std::chrono::milliseconds quiet,
                                            const std::atomic<bool> *cancelled = nullptr);
  // Wakes every wait, so that a wait whose `cancelled` was set ends.
  void interrupt();
  // Waits until the address is gone or exited.
  bool wait_gone(const std::string &address, std::chrono::steady_clock::time_point deadline);

private:
  // The addresses that have not registered (called with the mutex held).
  std::vector<std::string> missing(const std::vector<std::string> &addresses) const;

  struct Entry {
    bool registered = false;
    bool exited = false;
    std::string node;
    std::string why;
  };
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::map<std::string, Entry> entries_;
};

} // namespace rsca::domain
