// The runtime error of rsca: why a request failed, as every party to the control plane reports
// it. It travels in replies, so the values are part of the wire protocol. Findings in profiles
// keep their own type (common/diagnostic.hpp: file, line, column, rule); this one is for what
// goes wrong at run time.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json_fwd.hpp>
#include <tl/expected.hpp>

#include "common/diagnostic.hpp"

namespace rsca::protocol {

enum class Status : std::int32_t {
  Ok = 0,
  BadRequest = 1,  // the request makes no sense (unknown operation, malformed body)
  NotFound = 2,    // the thing named does not exist
  Failed = 3,      // the operation was tried and failed; the message says where and why
  Timeout = 4,     // no reply before the deadline
  Unavailable = 5, // nobody at the address, or the endpoint is shutting down
  Rejected = 6,    // refused by policy (admission control, conflicting state)
};
std::string_view to_string(Status status);
// The status a reply carries, or nothing for a number no version of rsca sends.
bool is_known(std::int32_t status);

struct CallError {
  Status status = Status::Failed;
  std::string message;
  // The addressee was there when the request was sent and may have acted on it: an Unavailable
  // call whose addressee left DDS before it replied, as opposed to one nobody ever served.
  bool maybe_received = false;
  // Every finding behind the message, when there are several to tell (a profile's, a value's):
  // each "file:line:column: rule: message", or "rule: message" where it has no place.
  std::vector<std::string> details{};
};

template <typename T>
using CallResult = tl::expected<T, CallError>;

inline tl::unexpected<CallError> call_error(Status status, std::string message) {
  return tl::unexpected(CallError{status, std::move(message)});
}

// A request that fails on findings (common/diagnostic.hpp: a name, a value, a profile): the
// message is the first one's, and `details` keeps them all, so that no conversion drops one.
tl::unexpected<CallError> call_error(Status status, const Error &findings);

// The details of an error reply, as its body carries them ({"details": [...], "maybe_received":
// true}), and back; a body without them gives none.
std::string error_body(const CallError &error);
// The same as a JSON object (empty without details), for a transport that carries JSON.
nlohmann::json error_body_json(const CallError &error);
std::vector<std::string> details_of(const nlohmann::json &body);
// Whether an error reply's body says the addressee may have acted on the request
// (CallError::maybe_received): a call relayed by a node (a CLI's over its control socket) keeps it.
bool maybe_received_of(const nlohmann::json &body);
std::vector<std::string> details_of_text(std::string_view body);

} // namespace rsca::protocol
