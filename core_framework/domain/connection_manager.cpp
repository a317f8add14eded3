#include "domain/connection_manager.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/content_filter.hpp"
#include "common/names.hpp"
#include "control/operation.hpp"
#include "dds/port_qos.hpp"
#include "domain/wiring.hpp"
#include "profile/connection_qos.hpp"
#include "protocol/topics.hpp"

namespace rsca::domain {

using control::CallResult;
using control::Json;
using control::Status;

std::string PortRef::to_string() const {
  switch (kind) {
  case Kind::Component:
    return owner + "/" + component + "." + port;
  case Kind::External:
  case Kind::Device:
    break;
  }
  return owner + "." + port;
}

namespace {

// Every name of an end can be a name (common/names.hpp): an end that breaks the rule can never
// exist, so it is refused at once instead of being kept pending. Checked here, the one path of
// every runtime connection (made, retried and restored), because the request is untrusted.
CallResult<void> check_end(const PortRef &end, const char *which) {
  auto refused = [which](const Error &error) {
    auto refusal = control::call_error(Status::BadRequest, error);
    refusal.value().message = fmt::format("{} end: {}", which, refusal.value().message);
    return refusal;
  };
  Expected<void> ok;
  if (end.kind == PortRef::Kind::Device) {
    const auto colon = end.owner.find(':');
    if (colon == std::string::npos)
      return control::call_error(
          Status::BadRequest,
          fmt::format("{} end: the device \"{}\" is not NODE:DEVICE", which, excerpt(end.owner)));
    ok = check_name("the node", std::string_view(end.owner).substr(0, colon)).and_then([&] {
      return check_name("the device", std::string_view(end.owner).substr(colon + 1));
    });
  } else {
    ok = check_name("the application", end.owner).and_then([&]() -> Expected<void> {
      if (end.kind == PortRef::Kind::Component)
        return check_name("the component", end.component);
      return {};
    });
  }
  ok = ok.and_then([&] { return check_name("the port", end.port); });
  if (!ok)
    return refused(ok.error());
  return {};
}

// The ends and the id a connection request gives, before anything is made or kept.
CallResult<void> check_request(const PortRef &uses, const PortRef &provides,
                               const std::string &id) {
  if (!id.empty())
    if (auto ok = check_name("the connection id", id); !ok)
      return control::call_error(Status::BadRequest, ok.error());
  return check_end(uses, "uses").and_then([&] { return check_end(provides, "provides"); });
}

} // namespace

ConnectionManager::ConnectionManager(std::string domain,
                                     const std::unique_ptr<control::Endpoint> &endpoint,
                                     Resolve resolve, std::chrono::milliseconds timeout)
    : domain_(std::move(domain)), endpoint_(endpoint), resolve_(std::move(resolve)),
      timeout_(timeout), retrier_([this] { retry_loop(); }) {}

void ConnectionManager::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (retrier_.joinable())
    retrier_.join();
}

namespace {

WireEnd wire_end(const RuntimeConnection &c, const ResolvedEnd &end, const PortRef &ref) {
  return {end.address, end.port, c.id, end.host, 1, fmt::format("{} ({})", c.id, ref.to_string()),
          end.via};
}

} // namespace

CallResult<void> ConnectionManager::wire(RuntimeConnection &c) {
  auto uses = resolve_(c.uses, profile::PortDirection::Uses);
  auto provides = resolve_(c.provides, profile::PortDirection::Provides);
  for (const auto *end : {&uses, &provides})
    if (!*end && end->error().status != Status::Unavailable)
      return tl::unexpected(end->error());
  if (uses && provides && uses->repid != provides->repid)
    return control::call_error(Status::BadRequest,
                               fmt::format("port type: {} sends {}, but {} takes {}",
                                           c.uses.to_string(), uses->repid, c.provides.to_string(),
                                           provides->repid));
  if (!uses || !provides) {
    c.waiting_for = (!uses ? uses : provides).error().message;
    return {};
  }
  c.repid = uses->repid;
  Wire w{wire_end(c, *uses, c.uses),
         wire_end(c, *provides, c.provides),
         c.topic,
         "",
         "",
         c.repid,
         c.qos,
         c.filter};
  std::vector<WireEnd> made;
  if (auto wired = Wiring(*endpoint_, timeout_).connect({w}, made); !wired) {
    // What was made is undone: a connection is made whole or not at all.
    for (const auto &failed : Wiring(*endpoint_, timeout_).disconnect(made))
      spdlog::warn("runtime connection {}: undoing an end failed: {}", c.id, failed);
    return control::call_error(wired.error().status,
                               fmt::format("connection {}: {}", c.id, wired.error().message));
  }
  c.uses_end = std::move(*uses);
  c.provides_end = std::move(*provides);
  c.waiting_for.clear();
  spdlog::info("runtime connection {}: {} -> {} on topic {}{}", c.id, c.uses.to_string(),
               c.provides.to_string(), c.topic, w.in_one_host() ? " (in its component host)" : "");
  return {};
}

void ConnectionManager::unwire(const RuntimeConnection &c,
                               const std::vector<const ResolvedEnd *> &ends) {
  std::vector<WireEnd> wire_ends;
  for (const auto *end : ends)
    wire_ends.push_back({end->address, end->port, c.id, end->host, 1, end->address, end->via});
  for (const auto &failed : Wiring(*endpoint_, timeout_).disconnect(wire_ends))
    spdlog::warn("runtime connection {}: an end was not disconnected: {}", c.id, failed);
}

CallResult<RuntimeConnection> ConnectionManager::connect(Request request) {
  if (auto ok = check_request(request.uses, request.provides, request.id); !ok)
    return tl::unexpected(ok.error());
  auto qos = dds::connection_qos_from_json(request.qos);
  if (!qos)
    return control::call_error(Status::BadRequest, qos.error().to_string());
  // A transport named that cannot carry the QoS asked for is refused, never silently weaker.
  if (auto why = profile::not_honoured(*qos, *qos->transport))
    return control::call_error(Status::BadRequest, *why);
  // A filter that does not parse would fail only when both ends are there: refused now.
  if (!request.filter.empty())
    if (auto filter = ContentFilter::parse(request.filter); !filter)
      return control::call_error(Status::BadRequest, fmt::format("filter: {}", filter.error()));
  std::lock_guard wiring(wiring_);
  RuntimeConnection c{std::move(request.id),
                      request.uses,
                      request.provides,
                      "",
                      "",
                      dds::qos_to_json(*qos),
                      std::move(request.filter),
                      "",
                      {},
                      {}};
  {
    std::lock_guard lock(mutex_);
    if (c.id.empty())
      do // past the ids of connections restored from the domain's store
        c.id = fmt::format("runtime_{}", ++next_);
      while (connections_.count(c.id) != 0);
    if (connections_.count(c.id) != 0)
      return control::call_error(Status::Rejected, fmt::format("a connection {} exists", c.id));
  }
  c.topic = protocol::runtime_connection_topic(domain_, c.id);
  if (auto ok = wire(c); !ok)
    return tl::unexpected(ok.error());
  if (!c.connected())
    spdlog::info("runtime connection {}: {} -> {} pending: {}", c.id, c.uses.to_string(),
                 c.provides.to_string(), c.waiting_for);
  std::lock_guard lock(mutex_);
  connections_[c.id] = c;
  return c;
}

CallResult<void> ConnectionManager::disconnect(const std::string &id) {
  std::lock_guard wiring(wiring_);
  RuntimeConnection c;
  {
    std::lock_guard lock(mutex_);
    auto it = connections_.find(id);
    if (it == connections_.end())
      return control::call_error(Status::NotFound, fmt::format("no runtime connection {}", id));
    c = std::move(it->second);
    connections_.erase(it);
  }
  if (c.connected())
    unwire(c, {&c.uses_end, &c.provides_end});
  spdlog::info("runtime connection {} removed", id);
  return {};
}

void ConnectionManager::owner_gone(const std::function<bool(const PortRef &)> &gone) {
  std::lock_guard wiring(wiring_);
  std::vector<RuntimeConnection> affected;
  {
    std::lock_guard lock(mutex_);
    for (auto &[id, c] : connections_) {
      if (!c.connected() || (!gone(c.uses) && !gone(c.provides)))
        continue;
      affected.push_back(c);
      c.waiting_for = fmt::format("{} is gone", gone(c.uses) ? c.uses.owner : c.provides.owner);
    }
  }
  for (const auto &c : affected) {
    std::vector<const ResolvedEnd *> remaining;
    if (!gone(c.uses))
      remaining.push_back(&c.uses_end);
    if (!gone(c.provides))
      remaining.push_back(&c.provides_end);
    unwire(c, remaining);
    spdlog::info("runtime connection {} pending again: an end is gone", c.id);
  }
}

void ConnectionManager::endpoints_changed() {
  {
    std::lock_guard lock(mutex_);
    retry_ = true;
  }
  wake_.notify_all();
}

void ConnectionManager::owner_gone_later(std::function<bool(const PortRef &)> gone) {
  {
    std::lock_guard lock(mutex_);
    gone_.push_back(std::move(gone));
  }
  wake_.notify_all();
}

void ConnectionManager::retry_loop() {
  for (;;) {
    bool retry = false;
    std::vector<std::function<bool(const PortRef &)>> gone;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return retry_ || !gone_.empty() || stopping_; });
      if (stopping_)
        return;
      retry = std::exchange(retry_, false);
      gone.swap(gone_);
    }
    for (const auto &g : gone)
      owner_gone(g);
    if (retry)
      retry_pending();
  }
}

void ConnectionManager::retry_pending() {
  std::lock_guard wiring(wiring_);
  std::vector<RuntimeConnection> pending;
  {
    std::lock_guard lock(mutex_);
    for (const auto &[id, c] : connections_)
      if (!c.connected())
        pending.push_back(c);
  }
  for (auto &c : pending) {
    if (auto ok = wire(c); !ok) {
      c.waiting_for = ok.error().message; // e.g. the port type of what appeared does not fit
      spdlog::warn("runtime connection {} cannot be completed: {}", c.id, c.waiting_for);
    }
    std::lock_guard lock(mutex_);
    if (auto it = connections_.find(c.id); it != connections_.end())
      it->second = c;
  }
}

std::vector<RuntimeConnection> ConnectionManager::list() const {
  std::lock_guard lock(mutex_);
  std::vector<RuntimeConnection> out;
  for (const auto &[id, c] : connections_)
    out.push_back(c);
  return out;
}

} // namespace rsca::domain
