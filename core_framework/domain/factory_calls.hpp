// Private to the ApplicationFactory (application_factory.cpp, launch.cpp, launch_wiring.cpp):
// calls made to many components at once, each named for the messages, and what they share.
#pragma once

#include <chrono>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "control/caller.hpp"
#include "control/operation.hpp"
#include "domain/application.hpp"
#include "profile/prf.hpp"

namespace rsca::domain::detail {

using Clock = std::chrono::steady_clock;
using control::CallResult;
using control::Json;
using control::Status;

// One call of many made at once.
struct Call {
  std::string target;
  std::string operation;
  Json body;
  std::string what; // for messages: "Producer_1"
};

// A call of operation `Op` (protocol/): its request typed, its `what` for messages.
template <control::Operation Op>
Call call_of(std::string target, const typename Op::Request &request, std::string what) {
  return {std::move(target), std::string(Op::name), protocol::encode(request), std::move(what)};
}

// Makes every call at once and waits for all of them; each result in the order of the calls.
// The components of one host get theirs in one request (control::Endpoint::call_all).
inline std::vector<CallResult<Json>> call_each_of(control::Caller &endpoint,
                                                  const std::vector<Call> &calls,
                                                  std::chrono::milliseconds timeout) {
  std::vector<control::Call> made;
  made.reserve(calls.size());
  for (const auto &c : calls)
    made.push_back({c.target, c.operation, c.body});
  return endpoint.call_all(made, timeout);
}

// The first failure among `results`, prefixed with its call's `what`.
template <typename T>
CallResult<void> first_failure(const std::vector<Call> &calls,
                               const std::vector<CallResult<T>> &results) {
  for (std::size_t i = 0; i < results.size(); ++i)
    if (!results[i])
      return control::call_error(results[i].error().status,
                                 fmt::format("{}: {}", calls[i].what, results[i].error().message));
  return {};
}

inline CallResult<void> call_all(control::Caller &endpoint, const std::vector<Call> &calls,
                                 std::chrono::milliseconds timeout) {
  return first_failure(calls, call_each_of(endpoint, calls, timeout));
}

// The processes an application's components run in: the components of a host share its process.
// What a node.execute may take beyond a call's time, to fetch `bytes` of files its cache lacks:
// at 4 MB/s, far below what a transfer runs at (docs/measurements.md), so that only a node that
// stopped fetching misses it.
inline std::chrono::milliseconds delivery_allowance(std::uint64_t bytes) {
  return std::chrono::milliseconds(bytes / 4000);
}

inline std::set<long> process_ids(const Application &app) {
  std::set<long> pids;
  for (const auto &c : app.components)
    if (c.pid != 0)
      pids.insert(c.pid);
  return pids;
}

inline bool is_execparam_only(const profile::PropertyDefinition &d) {
  const auto &c = profile::common_of(d);
  return c.has_kind(profile::PropertyKind::ExecParam) &&
         !c.has_kind(profile::PropertyKind::Configure) &&
         !c.has_kind(profile::PropertyKind::Property);
}

} // namespace rsca::domain::detail
