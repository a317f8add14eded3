// What a process's control presence offers, as an interface, whichever way it reaches the
// control plane: the Endpoint (control/endpoint.hpp), its own on DDS, or the NodeLink
// (control/node_link.hpp), through the node daemon that started it. The component runtime
// serves, calls and announces through this, and does not know which it has.
#pragma once

#include <chrono>
#include <functional>
#include <future>
#include <string>
#include <string_view>

#include "common/diagnostic.hpp"
#include "control/caller.hpp"

namespace rsca::control {

using protocol::CallError;
using protocol::Status;

struct RequestContext {
  std::string id;
  std::string sender;
  std::string operation;
  std::string target; // the address called: the endpoint's own or one of its aliases
  // When the request arrived: a handler that waits counts its time from here, as its caller
  // does, also when it ran late (after others of the same batch).
  std::chrono::steady_clock::time_point received = std::chrono::steady_clock::now();
};

using Handler = std::function<CallResult<Json>(const Json &body, const RequestContext &context)>;

// In an announcement's body: the endpoint that serves the announced address on its behalf (the
// node, for a process it started). Whoever follows announcements routes calls to the address
// there.
inline constexpr const char *kAnnouncedVia = "via";

class Server : public Caller {
public:
  virtual const std::string &address() const = 0;

  // Serves `operation` at every address served; a later registration replaces an earlier one.
  virtual void on(const std::string &operation, Handler handler) = 0;
  // Serves `operation` at `address` only, before any handler of on(operation).
  virtual void on(const std::string &address, const std::string &operation, Handler handler) = 0;
  // Drops the handlers of `address` and returns once none of them is running any more.
  virtual void stop_serving(const std::string &address) = 0;

  // A call fails at its deadline (Timeout), or at once when its addressee is known to be gone
  // (Unavailable).
  virtual std::future<CallResult<Json>> call(const std::string &target,
                                             const std::string &operation, Json body,
                                             std::chrono::milliseconds timeout) = 0;
  CallResult<Json> call_sync(const std::string &target, const std::string &operation, Json body,
                             std::chrono::milliseconds timeout) {
    return call(target, operation, std::move(body), timeout).get();
  }
  // Prepares the way for replies to `caller` ahead of its first request.
  virtual void prepare_replies(const std::string &caller) = 0;

  // Publishes (or updates) the announcement of `address`; withdraw removes it.
  virtual Expected<void> announce(const std::string &address, const std::string &kind,
                                  const Json &body) = 0;
  virtual void withdraw(const std::string &address) = 0;
};

} // namespace rsca::control
