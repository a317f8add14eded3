// ConnectionManager, runtime part: connections the operator makes and removes while the domain
// runs (`rsca connect` / `rsca disconnect`), between ports of running applications' components,
// applications' external ports and devices. A connection is checked before anything is made
// (both ends have the port in the right direction, and they carry the same port type) and gets a
// topic of its own. As REDHAWK's ConnectionManager, it waits for an end that is not there: a
// connection to an application not launched yet or a device whose node has not registered is
// pending, and is completed when the end appears; when an end goes (its application released,
// its node gone), the other end is disconnected and the connection is pending again. It lasts
// until it is disconnected.
#pragma once

#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "control/endpoint.hpp"
#include "profile/scd.hpp"

namespace rsca::domain {

// An end as the operator names it.
struct PortRef {
  enum class Kind : std::uint8_t {
    Component, // APP/COMPONENT.PORT
    External,  // APP.PORT: an external port of the application's SAD
    Device,    // NODE:DEVICE.PORT
  };
  Kind kind = Kind::Component;
  std::string owner;     // the application, or the device's id
  std::string component; // Component only
  std::string port;
  std::string to_string() const;
};

// Where an end is served once it exists.
struct ResolvedEnd {
  std::string address;
  std::string port; // the owner's port (an external port's is the component's)
  std::string repid;
  std::string host; // the component host that serves the owner, when it is hosted
  std::string via;  // the node that relays to the owner, when a node started its process
};

struct RuntimeConnection {
  std::string id;
  PortRef uses;
  PortRef provides;
  std::string topic;
  std::string repid;
  nlohmann::json qos;
  std::string filter;      // the provides end's content filter (common/content_filter.hpp)
  std::string waiting_for; // empty when connected; else what it waits for
  ResolvedEnd uses_end, provides_end;
  bool connected() const { return waiting_for.empty(); }
};

class ConnectionManager {
public:
  // Finds an end. Status::Unavailable means its owner is not there (yet): the connection waits;
  // any other error refuses it.
  using Resolve =
      std::function<control::CallResult<ResolvedEnd>(const PortRef &, profile::PortDirection)>;

  // `endpoint` may still be empty: the manager exists before the domain's endpoint opens (whose
  // announcements it hears), and calls through it only once connections are asked for.
  ConnectionManager(std::string domain, const std::unique_ptr<control::Endpoint> &endpoint,
                    Resolve resolve, std::chrono::milliseconds timeout);
  ~ConnectionManager() { stop(); }
  // Stops retrying (joins the manager's thread). Idempotent.
  void stop();
  ConnectionManager(const ConnectionManager &) = delete;
  ConnectionManager &operator=(const ConnectionManager &) = delete;

  // What a runtime connection is asked to be: `id` may be empty; `qos` has SAD <qos> names
  // (defaults are filled in); `filter`, a content filter for the provides end, may be empty.
  struct Request {
    PortRef uses;
    PortRef provides;
    std::string id;
    nlohmann::json qos = nlohmann::json::object();
    std::string filter;
  };

  // Connects uses → provides, as the wiring service makes a SAD's connections (the reader
  // first, then a wait until both ends match; in one component host without DDS). The result
  // is pending (waiting_for says for what) when an end is not there yet.
  control::CallResult<RuntimeConnection> connect(Request request);
  control::CallResult<void> disconnect(const std::string &id);
  // Something appeared (an application launched, a node registered): pending connections are
  // tried again, on the manager's own thread.
  void endpoints_changed();
  // An owner (application name, or device id) is going or gone: its connections are undone at
  // the other end and wait for it again. Only the other end is called: the gone one may not
  // answer.
  void owner_gone(const std::function<bool(const PortRef &)> &gone);
  // The same, done on the manager's own thread: for callers that must not block.
  void owner_gone_later(std::function<bool(const PortRef &)> gone);
  std::vector<RuntimeConnection> list() const;

private:
  // Makes both ends, or leaves the connection pending. Called with wiring_ held.
  control::CallResult<void> wire(RuntimeConnection &c);
  // Disconnects the ends given (best effort: a failure is logged).
  void unwire(const RuntimeConnection &c, const std::vector<const ResolvedEnd *> &ends);
  void retry_pending();
  void retry_loop();

  std::string domain_;
  const std::unique_ptr<control::Endpoint> &endpoint_;
  Resolve resolve_;
  std::chrono::milliseconds timeout_;

  std::mutex wiring_;        // one wiring change at a time (held across control calls)
  mutable std::mutex mutex_; // guards connections_ and the retry flags
  std::map<std::string, RuntimeConnection> connections_;
  std::uint64_t next_ = 0;
  std::condition_variable wake_;
  bool retry_ = false;
  std::vector<std::function<bool(const PortRef &)>> gone_; // owner_gone_later's, in order
  bool stopping_ = false;
  std::thread retrier_;
};

} // namespace rsca::domain
