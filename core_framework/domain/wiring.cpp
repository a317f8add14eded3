#include "domain/wiring.hpp"

#include <map>
#include <random>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "common/elapsed.hpp"
#include "dds/port_qos.hpp"
#include "domain/factory_calls.hpp"
#include "protocol/component_ops.hpp"

namespace rsca::domain {

using namespace detail;

namespace {

// The connection's QoS asks for a transport other than the nodes': DDS from each process itself
// (transport="direct") or a TCP stream between the two processes (transport="tcp").
profile::Transport transport_of(const Wire &wire) {
  const auto qos = dds::connection_qos_from_json(wire.qos);
  return qos ? *qos->transport : profile::Transport::Node;
}

// A TCP stream's token (profile "tcp"): 128 random bits, as hex, that only its two ends learn.
std::string new_token() {
  std::random_device random;
  std::string token;
  for (int i = 0; i < 4; ++i)
    token += fmt::format("{:08x}", random());
  return token;
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
  if (wire.through_node(end) && transport_of(wire) == profile::Transport::Node) {
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
  using Connect = protocol::component::Connect;
  // A TCP stream's two ends share a token; its writer connects where its reader listens, which
  // the reader's connect answers: readers first, then writers.
  std::vector<std::string> tokens(wires.size());
  std::vector<Call> readers;
  std::vector<const WireEnd *> reader_ends;
  std::vector<std::size_t> reader_wire;
  for (std::size_t i = 0; i < wires.size(); ++i) {
    const Wire &w = wires[i];
    const bool tcp = transport_of(w) == profile::Transport::Tcp && !w.in_one_host();
    if (tcp)
      tokens[i] = new_token();
    if (w.provides && !w.to_interface()) {
      auto request = connect_request(w, *w.provides, "provides");
      if (tcp)
        request.tcp_token = tokens[i];
      readers.push_back(call_of<Connect>(w.provides->address, request, w.provides->what));
      reader_ends.push_back(&*w.provides);
      reader_wire.push_back(i);
    }
  }
  WiringTimes times;
  auto began = Clock::now();
  const auto replies = call_each_of(caller_, readers, timeout_);
  std::vector<std::string> endpoints(wires.size());
  for (std::size_t k = 0; k < replies.size(); ++k) {
    if (!replies[k])
      continue;
    made.push_back(*reader_ends[k]);
    auto reply = protocol::decode<protocol::component::ConnectReply>(*replies[k]);
    if (reply && reply->tcp_endpoint)
      endpoints[reader_wire[k]] = *reply->tcp_endpoint;
  }
  if (auto ok = first_failure(readers, replies); !ok)
    return tl::unexpected(ok.error());
  times.readers_ms = ms_since(began);

  std::vector<Call> writers;
  std::vector<const WireEnd *> writer_ends;
  for (std::size_t i = 0; i < wires.size(); ++i) {
    const Wire &w = wires[i];
    if (!w.uses)
      continue;
    auto request = connect_request(w, *w.uses, "uses");
    if (!tokens[i].empty()) {
      if (endpoints[i].empty())
        return control::call_error(
            Status::Failed,
            fmt::format("{}: its reader gave no TCP endpoint to connect to", w.uses->what));
      request.tcp_peer = endpoints[i];
      request.tcp_token = tokens[i];
    }
    writers.push_back(call_of<Connect>(w.uses->address, request, w.uses->what));
    writer_ends.push_back(&*w.uses);
  }
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
