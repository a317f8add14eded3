// Who serves what at an endpoint: handlers by address and operation, relays by address, and the
// handlers running, so that dropping an address can wait for them. The Endpoint (DDS) and the
// NodeLink (the node link) both serve through one.
#pragma once

#include <condition_variable>
#include <future>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

#include "control/server.hpp"

namespace rsca::control {

// Hands a call on (a node, to the process it started): starts it, returns its result to come,
// and must not block.
using RelayHandler =
    std::function<std::future<CallResult<Json>>(const Json &body, const RequestContext &context)>;

class HandlerTable {
public:
  // `address` empty: at every address served.
  void on(const std::string &address, const std::string &operation, Handler handler);
  void relay(const std::string &address, RelayHandler handler);
  // Drops the handlers and the relay of `address` and returns once none of them runs any more.
  void drop(const std::string &address);
  // Drops the relay of `address` and returns at once: relayed calls under way end on their own
  // (their process is gone), and waiting here could wait on the very thread that reports it.
  void drop_relay(const std::string &address);

  // Runs the handler for the call's address and operation (a relay, when the address has one);
  // "bad request" when there is none. A handler that throws on a malformed body (JSON's type
  // errors) answers "bad request" too; another exception "failed".
  CallResult<Json> dispatch(const RequestContext &context, const Json &body);
  // A call to a relayed address, started: its result to come (none when the address is not
  // relayed). finish() waits for it; the address counts as running until then.
  std::optional<std::future<CallResult<Json>>> start_relay(const RequestContext &context,
                                                           const Json &body);
  CallResult<Json> finish(const std::string &target, std::future<CallResult<Json>> started);

private:
  void done(const std::string &target);

  std::mutex mutex_;
  std::condition_variable done_;
  std::map<std::pair<std::string, std::string>, Handler> handlers_; // (address or "", operation)
  std::map<std::string, RelayHandler> relays_;                      // by address
  std::map<std::string, int> running_;                              // by address
};

} // namespace rsca::control
