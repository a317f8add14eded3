// What a domain service asks of the control plane, as an interface: the Endpoint is the real
// one; a unit test fakes it to see every call a service makes and to fail any of them (the
// launch's rollback is tested so, step by step).
#pragma once

#include <chrono>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "protocol/status.hpp"

namespace rsca::control {

using Json = nlohmann::json;
using protocol::CallResult;

// One call of many made at once (Caller::call_all).
struct Call {
  std::string target;
  std::string operation;
  Json body;
};

class Caller {
public:
  virtual ~Caller() = default;
  // Makes every call at once and waits for all; each result in the order of the calls.
  virtual std::vector<CallResult<Json>> call_all(const std::vector<Call> &calls,
                                                 std::chrono::milliseconds timeout) = 0;
  // Calls to `target` go to `via`, the endpoint that serves it as an alias.
  virtual void route(const std::string &target, const std::string &via) = 0;
  // Creates the way to `target` ahead of the first call.
  virtual void prepare(const std::string &target) = 0;
  // Drops the way to and from `target` (an endpoint that is gone for good), and its route.
  virtual void forget(const std::string &target) = 0;
};

} // namespace rsca::control
