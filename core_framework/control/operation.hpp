// The operations of the control plane, typed: each is one type in protocol/ (its name, its
// request and its reply), and both sides of a contract use it, so the compiler checks them
// against each other:
//
//   serve<protocol::node::Terminate>(endpoint, [](const auto &request, const auto &) {...});
//   auto reply = call<protocol::node::Terminate>(endpoint, node, {.pid = pid}, timeout);
//
// A request that does not decode is answered "bad request" with what is wrong, before any
// handler runs; a reply that does not decode fails the call.
#pragma once

#include <chrono>
#include <concepts>
#include <future>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "control/endpoint.hpp"
#include "protocol/codec.hpp"

namespace rsca::control {

template <typename Op>
concept Operation = requires {
  { Op::name } -> std::convertible_to<std::string_view>;
  requires protocol::MessageType<typename Op::Request>;
  requires protocol::MessageType<typename Op::Reply>;
};

// A request of operation `Op` made into an untyped call (for Endpoint::call_all).
template <Operation Op>
Call make_call(std::string target, const typename Op::Request &request) {
  return {std::move(target), std::string(Op::name), protocol::encode(request)};
}

// A reply of `Op` read: a reply that does not fit the contract fails the call.
template <Operation Op>
CallResult<typename Op::Reply> reply_of(CallResult<Json> raw) {
  if (!raw)
    return tl::unexpected(std::move(raw.error()));
  auto reply = protocol::decode<typename Op::Reply>(*raw);
  if (!reply)
    return call_error(Status::Failed,
                      fmt::format("malformed reply to {}: {}", Op::name, reply.error()));
  return std::move(*reply);
}

template <Operation Op>
CallResult<typename Op::Reply> call(Server &endpoint, const std::string &target,
                                    const typename Op::Request &request,
                                    std::chrono::milliseconds timeout) {
  return reply_of<Op>(
      endpoint.call_sync(target, std::string(Op::name), protocol::encode(request), timeout));
}

// A call whose reply nobody waits for (a report): its result is dropped when it comes.
template <Operation Op>
void send(Server &endpoint, const std::string &target, const typename Op::Request &request,
          std::chrono::milliseconds timeout) {
  endpoint.call(target, std::string(Op::name), protocol::encode(request), timeout);
}

template <Operation Op>
using OperationHandler = std::function<CallResult<typename Op::Reply>(const typename Op::Request &,
                                                                      const RequestContext &)>;

// The untyped handler that decodes the request, runs `handler` and encodes its reply.
template <Operation Op>
Handler typed_handler(OperationHandler<Op> handler) {
  return [handler = std::move(handler)](const Json &body,
                                        const RequestContext &context) -> CallResult<Json> {
    auto request = protocol::decode<typename Op::Request>(body);
    if (!request)
      return call_error(Status::BadRequest, fmt::format("{}: {}", Op::name, request.error()));
    auto reply = handler(*request, context);
    if (!reply)
      return tl::unexpected(std::move(reply.error()));
    return protocol::encode(*reply);
  };
}

// Serves `Op` at every address of `endpoint`.
template <Operation Op>
void serve(Server &endpoint, OperationHandler<Op> handler) {
  endpoint.on(std::string(Op::name), typed_handler<Op>(std::move(handler)));
}

// Serves `Op` at `address` only (the endpoint's own or an alias).
template <Operation Op>
void serve(Server &endpoint, const std::string &address, OperationHandler<Op> handler) {
  endpoint.on(address, std::string(Op::name), typed_handler<Op>(std::move(handler)));
}

} // namespace rsca::control
