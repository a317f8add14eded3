#include "control/handler_table.hpp"

#include <fmt/format.h>

namespace rsca::control {

void HandlerTable::on(const std::string &address, const std::string &operation, Handler handler) {
  std::lock_guard lock(mutex_);
  handlers_[{address, operation}] = std::move(handler);
}

void HandlerTable::relay(const std::string &address, RelayHandler handler) {
  std::lock_guard lock(mutex_);
  relays_[address] = std::move(handler);
}

void HandlerTable::drop(const std::string &address) {
  std::unique_lock lock(mutex_);
  std::erase_if(handlers_, [&](const auto &entry) { return entry.first.first == address; });
  relays_.erase(address);
  done_.wait(lock, [&] { return !running_.contains(address); });
}

void HandlerTable::drop_relay(const std::string &address) {
  std::lock_guard lock(mutex_);
  relays_.erase(address);
}

void HandlerTable::done(const std::string &target) {
  {
    std::lock_guard lock(mutex_);
    if (--running_[target] == 0)
      running_.erase(target);
  }
  done_.notify_all();
}

std::optional<std::future<CallResult<Json>>>
HandlerTable::start_relay(const RequestContext &context, const Json &body) {
  RelayHandler relay;
  {
    std::lock_guard lock(mutex_);
    auto it = relays_.find(context.target);
    if (it == relays_.end())
      return std::nullopt;
    relay = it->second;
    ++running_[context.target];
  }
  return relay(body, context);
}

CallResult<Json> HandlerTable::finish(const std::string &target,
                                      std::future<CallResult<Json>> started) {
  CallResult<Json> result = started.get();
  done(target);
  return result;
}

CallResult<Json> HandlerTable::dispatch(const RequestContext &context, const Json &body) {
  if (auto started = start_relay(context, body))
    return finish(context.target, std::move(*started));
  Handler handler;
  {
    std::lock_guard lock(mutex_);
    auto it = handlers_.find({context.target, context.operation});
    if (it == handlers_.end())
      it = handlers_.find({std::string(), context.operation});
    if (it == handlers_.end())
      return call_error(Status::BadRequest, fmt::format("{} does not serve operation \"{}\"",
                                                        context.target, context.operation));
    handler = it->second;
    ++running_[context.target];
  }
  CallResult<Json> result = [&]() -> CallResult<Json> {
    // A request is untrusted: a handler that reads a field of the wrong type answers BadRequest
    // instead of ending the process.
    try {
      return handler(body, context);
    } catch (const Json::exception &e) {
      return call_error(Status::BadRequest,
                        fmt::format("malformed \"{}\" request: {}", context.operation, e.what()));
    } catch (const std::exception &e) {
      return call_error(Status::Failed, e.what());
    }
  }();
  done(context.target);
  return result;
}

} // namespace rsca::control
