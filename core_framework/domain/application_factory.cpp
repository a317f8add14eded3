#include "domain/application_factory.hpp"

#include <algorithm>
#include <set>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "domain/launch.hpp"
#include "domain/wiring.hpp"
#include "protocol/component_ops.hpp"

namespace rsca::domain {

using namespace detail;

CallResult<std::shared_ptr<Application>> ApplicationFactory::create(const LaunchRequest &request,
                                                                    const ProgressSink &progress) {
  return Launch(services_, request, progress).run();
}

namespace {

// Exited, or on a node that is lost: not called, since it cannot answer.
bool exited(const ComponentInstance &c) {
  return c.state == ComponentState::Exited || c.state == ComponentState::Unreachable;
}

// Marks the components `ids` names as `state`, except those that exited (or became unreachable)
// meanwhile.
void mark(Application &app, const std::vector<std::string> &ids, ComponentState state) {
  for (const auto &id : ids)
    if (auto *c = app.find_component(id); c != nullptr && !exited(*c))
      c->state = state;
}

} // namespace

CallResult<void> ApplicationFactory::start(const Application &app, const ApplyChange &apply) {
  // In start order (the assembly controller first among equals, on its own); the components of
  // one start order at once. A component that exited is not called: it cannot answer.
  std::vector<const ComponentInstance *> order;
  for (const auto &c : app.components)
    if (!exited(c))
      order.push_back(&c);
  std::stable_sort(order.begin(), order.end(), [](const auto *a, const auto *b) {
    if (a->start_order != b->start_order)
      return a->start_order < b->start_order;
    return a->assembly_controller && !b->assembly_controller;
  });
  for (auto group = order.begin(); group != order.end();) {
    auto end = std::next(group);
    if (!(*group)->assembly_controller)
      end = std::find_if(end, order.end(),
                         [&](const auto *c) { return c->start_order != (*group)->start_order; });
    std::vector<Call> calls;
    std::vector<std::string> ids;
    for (; group != end; ++group) {
      calls.push_back(call_of<protocol::component::Start>((*group)->address, {}, (*group)->id));
      ids.push_back((*group)->id);
    }
    if (auto ok = call_all(*services_.endpoint, calls, services_.call_timeout); !ok)
      return ok;
    apply([&ids](Application &a) { mark(a, ids, ComponentState::Running); });
  }
  apply([](Application &a) { a.state = ApplicationState::Running; });
  return {};
}

CallResult<void> ApplicationFactory::stop(const Application &app, const ApplyChange &apply) {
  std::vector<Call> calls;
  std::vector<std::string> ids;
  for (const auto &c : app.components)
    if (!exited(c)) {
      calls.push_back(call_of<protocol::component::Stop>(c.address, {}, c.id));
      ids.push_back(c.id);
    }
  const auto replies = call_each_of(*services_.endpoint, calls, services_.call_timeout);
  // Those that confirmed are stopped; the state of those that did not answer is not known.
  std::vector<std::string> stopped;
  for (std::size_t i = 0; i < replies.size(); ++i)
    if (replies[i])
      stopped.push_back(ids[i]);
  apply([&stopped](Application &a) {
    mark(a, stopped, ComponentState::Stopped);
    a.state = ApplicationState::Stopped;
  });
  return first_failure(calls, replies);
}

// Devices outlive the application: their ends of its connections go first.
std::size_t ApplicationFactory::disconnect_devices(const Application &app) {
  std::vector<WireEnd> ends;
  for (const auto &ci : app.connections)
    for (const auto *end : {&ci.uses, &ci.provides})
      if (!end->device.empty())
        ends.push_back({.address = end->address,
                        .port = end->port,
                        .connection = end_key(ci, *end),
                        .host = {},
                        .peers = 1,
                        .what = fmt::format("{} ({})", ci.id, end->name()),
                        .node = {}});
  for (const auto &failed : Wiring(*services_.endpoint, services_.call_timeout).disconnect(ends))
    spdlog::warn("application {}: a device end was not disconnected: {}", app.name, failed);
  return ends.size();
}

CallResult<ApplicationFactory::ProcessesReleased> ApplicationFactory::release(Application &app) {
  disconnect_devices(app);
  auto released = release_processes(app);
  services_.allocator->release(app.plan);
  app.plan = {};
  services_.channels->leave(app.name);
  return released;
}

CallResult<ApplicationFactory::ProcessesReleased>
ApplicationFactory::release_processes(Application &app) {
  ProcessesReleased outcome;
  std::vector<Call> releases;
  for (auto &c : app.components)
    if (c.pid != 0 && services_.components->registered(c.address))
      releases.push_back(call_of<protocol::component::Release>(c.address, {}, c.id));
  const auto released = call_each_of(*services_.endpoint, releases, services_.call_timeout);
  for (std::size_t i = 0; i < released.size(); ++i) {
    if (released[i])
      continue;
    spdlog::warn("{} of application {} did not confirm its release ({}); its node terminates it",
                 releases[i].what, app.name, released[i].error().message);
    outcome.unconfirmed.push_back(releases[i].what);
  }
  // Whatever is still running is terminated by its node; the node reaps every process. One its
  // node cannot be asked to end now (the node is lost) is ended when the node is back.
  std::set<long> deferred_pids;
  const auto end_later = [&](const ComponentInstance &c) {
    if (!services_.end_when_back)
      return;
    spdlog::warn("application {}: process {} of {} is ended when its node {} is back", app.name,
                 c.pid, c.id, c.node);
    services_.end_when_back(c.node, c.pid, fmt::format("{}/{}", app.name, c.id));
    ++outcome.deferred;
    deferred_pids.insert(c.pid);
  };
  std::vector<Call> terminations;
  std::vector<const ComponentInstance *> terminated_of; // per termination
  std::set<long> terminated_pids; // the components of a host share its process
  for (auto &c : app.components) {
    if (c.pid == 0 || !terminated_pids.insert(c.pid).second)
      continue;
    auto node = services_.node_address(c.node);
    if (!node) {
      end_later(c);
      continue;
    }
    terminations.push_back(call_of<protocol::node::Terminate>(*node, {c.pid}, c.id));
    terminated_of.push_back(&c);
  }
  auto terminated = call_each_of(*services_.endpoint, terminations, services_.call_timeout);
  std::optional<control::CallError> failure;
  for (std::size_t i = 0; i < terminated.size(); ++i) {
    if (terminated[i]) {
      ++outcome.terminated;
      continue;
    }
    const Status status = terminated[i].error().status;
    if (status == Status::NotFound) // it had ended
      continue;
    if (status == Status::Unavailable || status == Status::Timeout)
      end_later(*terminated_of[i]); // its node went away, or does not answer
    else if (!failure)
      failure = control::CallError{
          status, fmt::format("{}: {}", terminations[i].what, terminated[i].error().message)};
  }
  // Those of a process left running for now were not terminated by their node: said as they are.
  for (const auto &c : app.components)
    if (deferred_pids.count(c.pid) != 0) {
      outcome.lost.push_back({c.id, c.node});
      std::erase(outcome.unconfirmed, c.id);
    }
  for (auto &c : app.components) {
    services_.components->forget(c.address);
    services_.endpoint->forget(c.address);
    if (!c.host.empty())
      services_.endpoint->forget(c.host);
    c.state = ComponentState::Released;
    c.pid = 0;
  }
  if (failure)
    return tl::unexpected(*failure);
  return outcome;
}

} // namespace rsca::domain
