// Calls: sending them, their replies, deadlines and departures, batches and routes.
#include "control/endpoint_impl.hpp"

#include <algorithm>
#include <set>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "control.h" // generated from dds/control.idl

namespace rsca::control {

using namespace detail;

void Endpoint::Impl::complete(const std::string &id, CallResult<Json> result) {
  std::unique_lock lock(state_mutex);
  auto it = pending.find(id);
  if (it == pending.end())
    return; // already timed out, or not ours
  auto promise = std::move(it->second.promise);
  pending.erase(it);
  lock.unlock();
  promise.set_value(std::move(result));
}

void Endpoint::Impl::fail_calls(
    const std::function<std::optional<CallError>(const Pending &)> &failure) {
  std::vector<std::pair<std::promise<CallResult<Json>>, CallError>> failed;
  {
    std::lock_guard lock(state_mutex);
    for (auto it = pending.begin(); it != pending.end();) {
      auto error = failure(it->second);
      if (!error) {
        ++it;
        continue;
      }
      failed.emplace_back(std::move(it->second.promise), std::move(*error));
      it = pending.erase(it);
    }
  }
  for (auto &[promise, error] : failed)
    promise.set_value(tl::unexpected(std::move(error)));
}

void Endpoint::Impl::expire_calls() {
  const auto now = Clock::now();
  fail_calls([now](const Pending &p) -> std::optional<CallError> {
    if (p.deadline > now)
      return std::nullopt;
    if (p.sent)
      return CallError{
          Status::Timeout,
          fmt::format("no reply from {} to \"{}\" before the deadline", p.target, p.operation)};
    return CallError{Status::Unavailable, fmt::format("nobody serves address {}", p.target)};
  });
}

// A call whose addressee left DDS after it was sent (its process exited, or lost its lease)
// fails now instead of at its deadline: a CLI whose domain daemon died during a launch says so
// within a lease, not after six times its timeout (issue 18, defect 10).
void Endpoint::Impl::fail_calls_to_departed() {
  const auto now = Clock::now();
  if (now - departures_checked < kDepartureCheck)
    return;
  departures_checked = now;
  {
    std::lock_guard lock(state_mutex);
    if (std::none_of(pending.begin(), pending.end(), [](const auto &p) { return p.second.sent; }))
      return;
  }
  const std::set<std::string> gone = request_ways->departed();
  if (gone.empty())
    return;
  std::map<std::string, std::string> via;
  {
    std::lock_guard lock(routes_mutex);
    via = routes;
  }
  fail_calls([&](const Pending &p) -> std::optional<CallError> {
    auto route = via.find(p.target);
    if (!p.sent || gone.count(route != via.end() ? route->second : p.target) == 0)
      return std::nullopt;
    return CallError{Status::Unavailable,
                     fmt::format("{} left before it replied to \"{}\": its endpoint is gone from "
                                 "DDS (the process exited or lost its lease)",
                                 p.target, p.operation),
                     /*maybe_received=*/true};
  });
}

void Endpoint::Impl::send_request(std::string id, std::string target, std::string operation,
                                  std::string body) {
  Clock::time_point deadline;
  {
    std::lock_guard lock(state_mutex);
    auto it = pending.find(id);
    if (it == pending.end())
      return; // expired before it could be sent
    deadline = it->second.deadline;
  }
  auto writer = request_ways->matched_writer(route_of(target), deadline, stopping);
  if (!writer) {
    complete(id, tl::unexpected(writer.error()));
    return;
  }
  {
    // The addressee is matched: from here silence is a timeout, also when the deadline passes
    // during the write, and never "nobody serves" for a request it may well have received.
    std::lock_guard lock(state_mutex);
    auto it = pending.find(id);
    if (it == pending.end())
      return; // expired while its addressee was awaited
    it->second.sent = true;
  }
  rsca_ctl_Request request{};
  request.id = id.data();
  request.sender = address.data();
  request.target = target.data();
  request.operation = operation.data();
  request.body = body.data();
  if (dds_return_t rc = dds_write(*writer, &request); rc < 0) {
    complete(id, call_error(Status::Failed,
                            fmt::format("sending to {} failed: {}", target, dds_strretcode(rc))));
    return;
  }
}

std::string Endpoint::Impl::route_of(const std::string &target) {
  std::lock_guard lock(routes_mutex);
  auto it = routes.find(target);
  return it != routes.end() ? it->second : target;
}

std::vector<CallResult<Json>> Endpoint::call_all(const std::vector<Call> &calls,
                                                 std::chrono::milliseconds timeout) {
  // Calls to the addresses one endpoint serves, by that endpoint: two and more go as a batch.
  std::map<std::string, std::vector<std::size_t>> by_endpoint;
  for (std::size_t i = 0; i < calls.size(); ++i)
    by_endpoint[impl_->route_of(calls[i].target)].push_back(i);
  std::vector<std::future<CallResult<Json>>> single(calls.size());
  std::vector<std::pair<std::vector<std::size_t>, std::future<CallResult<Json>>>> batches;
  for (auto &[via, indexes] : by_endpoint) {
    const bool routed = via != calls[indexes.front()].target;
    if (!routed || indexes.size() < 2) {
      for (auto i : indexes)
        single[i] = call(calls[i].target, calls[i].operation, calls[i].body, timeout);
      continue;
    }
    Json items = Json::array();
    for (auto i : indexes)
      items.push_back({{"target", calls[i].target},
                       {"operation", calls[i].operation},
                       {"body", calls[i].body}});
    batches.emplace_back(indexes, call(via, kBatch, Json{{"calls", std::move(items)}}, timeout));
  }
  std::vector<CallResult<Json>> results(calls.size(), call_error(Status::Failed, "not made"));
  for (auto &[indexes, future] : batches) {
    auto reply = future.get();
    const Json none = Json::array();
    const Json &items = reply ? reply->value("results", none) : none;
    for (std::size_t k = 0; k < indexes.size(); ++k)
      results[indexes[k]] = !reply ? CallResult<Json>(tl::unexpected(reply.error()))
                            : k < items.size()
                                ? result_of(items[k])
                                : call_error(Status::Failed, "the batch reply is short");
  }
  for (std::size_t i = 0; i < calls.size(); ++i)
    if (single[i].valid())
      results[i] = single[i].get();
  return results;
}

void Endpoint::route(const std::string &target, const std::string &via) {
  std::lock_guard lock(impl_->routes_mutex);
  impl_->routes[target] = via;
}

std::future<CallResult<Json>> Endpoint::call(const std::string &target,
                                             const std::string &operation, Json body,
                                             std::chrono::milliseconds timeout) {
  std::future<CallResult<Json>> future;
  std::string id;
  {
    std::lock_guard lock(impl_->state_mutex);
    id = call_id(impl_->address, ++impl_->next_id);
    Impl::Pending pending{{}, Clock::now() + timeout, target, operation};
    future = pending.promise.get_future();
    impl_->pending.emplace(id, std::move(pending));
  }
  impl_->wake(); // the receiver recomputes its timeout
  impl_->send_pool->post([impl = impl_.get(), id, target, operation, text = body.dump()]() mutable {
    impl->send_request(std::move(id), std::move(target), std::move(operation), std::move(text));
  });
  return future;
}

void Endpoint::abandon(const std::string &target, const std::string &why) {
  impl_->fail_calls([&](const Impl::Pending &p) -> std::optional<CallError> {
    if (p.target != target)
      return std::nullopt;
    return CallError{Status::Unavailable,
                     fmt::format("{} to \"{}\": {}", p.target, p.operation, why)};
  });
}

} // namespace rsca::control
