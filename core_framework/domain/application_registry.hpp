// ApplicationRegistry: the running applications, the one owner of their state.
//
// A launch first reserves its name: the application is *launching*, not yet found by name, but
// its name is taken and the installed application it comes from cannot be uninstalled. A launch
// that succeeds commits its application; one that fails drops the reservation. Every change of an
// application's or a component's state happens through update() under the registry's lock, and
// readers get copies made under it, so a reader never sees a state half written. Start, stop and
// release of one application are serialized by that application's lifecycle lock: a stop never
// interleaves with a start of the same application.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "control/endpoint.hpp"
#include "domain/application.hpp"

namespace rsca::domain {

class ApplicationRegistry {
public:
  // A running application and the lock that serializes its start, stop and release. The
  // application's mutable state (its state, its components' states) is read and written only
  // through the registry; what a launch fixed (addresses, connections, plan) may be read freely.
  struct Handle {
    std::shared_ptr<Application> app;
    std::shared_ptr<std::mutex> lifecycle;
  };

  // Reserves a name for a launch of `installed`: `wanted` itself when `exact` (Rejected when
  // taken), else `wanted` or the first free `wanted_N`.
  control::CallResult<std::string> reserve(const std::string &wanted, bool exact,
                                           const std::string &installed);
  // A launch that failed gives its name back.
  void drop(const std::string &name);
  // A launch that succeeded: its application runs under the name it reserved.
  void commit(std::shared_ptr<Application> app);
  // Whether a launch of `installed` is under way.
  bool launching(const std::string &installed) const;

  control::CallResult<Handle> find(const std::string &name) const;
  // Takes a running application out (it is being released); nothing finds it any more.
  std::optional<Handle> remove(const std::string &name);

  // Applies `change` to a running application under the lock; false when none runs so named.
  bool update(const std::string &name, const std::function<void(Application &)> &change);
  // Applies `change` to every running application under the lock.
  void update_all(const std::function<void(Application &)> &change);
  // A copy of a running application, made under the lock.
  std::optional<Application> snapshot(const std::string &name) const;
  // Copies of all running applications, made under the lock.
  std::vector<Application> snapshots() const;
  std::vector<std::string> running_from(const std::string &installed) const;

private:
  struct Entry {
    std::string installed;
    Handle handle; // no application while launching
  };
  bool taken(const std::string &name) const { return entries_.count(name) != 0; }

  mutable std::mutex mutex_;
  std::map<std::string, Entry> entries_;
};

} // namespace rsca::domain
