#include "domain/wiring.hpp"

#include <map>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "common/elapsed.hpp"
#include "dds/port_qos.hpp"
#include "domain/factory_calls.hpp"
#include "protocol/component_ops.hpp"

namespace rsca::domain {

using namespace detail;

namespace {

// The connection's QoS asks each process to carry it on DDS itself (transport="direct").
bool asks_direct_dds(const Wire &wire) {
  const auto qos = dds::connection_qos_from_json(wire.qos);
  return qos && qos->transport == profile::Transport::Direct;
}

protocol::component::ConnectRequest connect_request(const Wire &wire, const WireEnd &end,
                                                    const char *direction) {
  protocol::component::ConnectRequest request;
  request.connection = end.connection;
  request.port = end.port;
  request.direction = direction;
  request.repid = wire.repid;
  if (wire.to_interface()) {
    request.target = wire.interface_target;
    if (!wire.interface_via.empty())
      request.via = wire.interface_via;
    return request;
  }
  request.topic = wire.topic;
  request.qos = wire.qos;
  const bool reader = std::string_view(direction) == "provides";
  request.filter = reader ? wire.filter : "";
  request.local = wire.in_one_host();
  if (wire.through_node(end) && !asks_direct_dds(wire)) {
    request.shared_memory = true;
    request.relay = !wire.on_one_node(); // ends on other hosts, or an event channel's
  }
  return request;
}

// Makes `calls` at once; the ends whose call succeeded go to `made`.
CallResult<void> connect_all(control::Caller &caller, const std::vector<Call> &calls,
                             const std::vector<const WireEnd *> &ends,
                             std::chrono::milliseconds timeout, std::vector<WireEnd> &made) {
  const auto replies = call_each_of(caller, calls, timeout);
  for (std::size_t i = 0; i < replies.size(); ++i)
    if (replies[i])
      made.push_back(*ends[i]);
  return first_failure(calls, replies);
}

} // namespace

CallResult<WiringTimes> Wiring::connect(const std::vector<Wire> &wires,
                                        std::vector<WireEnd> &made) {
  std::vector<Call> readers, writers;
  std::vector<const WireEnd *> reader_ends, writer_ends;
  using Connect = protocol::component::Connect;
  for (const auto &w : wires) {
    if (w.provides && !w.to_interface()) {
      readers.push_back(call_of<Connect>(
          w.provides->address, connect_request(w, *w.provides, "provides"), w.provides->what));
      reader_ends.push_back(&*w.provides);
    }
    if (w.uses) {
      writers.push_back(
          call_of<Connect>(w.uses->address, connect_request(w, *w.uses, "uses"), w.uses->what));
      writer_ends.push_back(&*w.uses);
    }
  }
  WiringTimes times;
  auto began = Clock::now();
  if (auto ok = connect_all(caller_, readers, reader_ends, timeout_, made); !ok)
    return tl::unexpected(ok.error());
  times.readers_ms = ms_since(began);
  began = Clock::now();
  if (auto ok = connect_all(caller_, writers, writer_ends, timeout_, made); !ok)
    return tl::unexpected(ok.error());
  times.writers_ms = ms_since(began);
  began = Clock::now();
  if (auto ok = await_matched(wires); !ok)
    return tl::unexpected(ok.error());
  times.matched_ms = ms_since(began);
  return times;
}

// One request per address for all the ends it serves, all addresses at once, each answered when
// its ends have matched or its wait ran out (counted from the request's arrival).
CallResult<void> Wiring::await_matched(const std::vector<Wire> &wires) {
  std::map<std::string, protocol::component::AwaitMatchedRequest> awaited; // by address
  auto await = [&](const std::optional<WireEnd> &end) {
    if (!end || end->peers == 0)
      return;
    auto &request = awaited[end->address];
    request.timeout_ms = timeout_.count();
    request.connections.push_back({end->port, end->connection, end->peers, 0});
  };
  for (const auto &w : wires) {
    if (w.to_interface())
      continue; // a control address: nothing to discover
    await(w.uses);
    await(w.provides);
  }
  std::vector<Call> calls;
  for (auto &[address, request] : awaited)
    calls.push_back(call_of<protocol::component::AwaitMatched>(address, request, address));
  auto replies = call_each_of(caller_, calls, 2 * timeout_);
  if (auto ok = first_failure(calls, replies); !ok)
    return ok;
  std::vector<std::string> unmatched;
  for (auto &raw : replies) {
    auto reply = control::reply_of<protocol::component::AwaitMatched>(std::move(raw));
    if (!reply)
      return tl::unexpected(reply.error());
    for (const auto &c : reply->connections)
      if (c.matched < c.peers)
        unmatched.push_back(fmt::format("{} on port {}: {} of {} peers matched", c.connection,
                                        c.port, c.matched, c.peers));
  }
  if (!unmatched.empty())
    return control::call_error(Status::Unavailable,
                               fmt::format("connections not matched after {} ms: {}",
                                           timeout_.count(), fmt::join(unmatched, "; ")));
  return {};
}

std::vector<std::string> Wiring::disconnect(const std::vector<WireEnd> &ends) {
  std::vector<Call> calls;
  for (const auto &end : ends)
    calls.push_back(call_of<protocol::component::Disconnect>(end.address,
                                                             {end.connection, end.port}, end.what));
  const auto replies = call_each_of(caller_, calls, timeout_);
  std::vector<std::string> failed;
  for (std::size_t i = 0; i < replies.size(); ++i)
    if (!replies[i])
      failed.push_back(fmt::format("{}: {}", calls[i].what, replies[i].error().message));
  return failed;
}

} // namespace rsca::domain
