// The DomainManager's operations on running components: configure and query (a component of an
// application, or a device), and what nodes and components report to the domain (processes that
// exited, connection problems).
#include <algorithm>
#include <sstream>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/names.hpp"
#include "control/operation.hpp"
#include "domain/domain_manager_impl.hpp"
#include "profile/property_binding.hpp"
#include "profile/property_json.hpp"
#include "protocol/component_ops.hpp"
#include "protocol/json_text.hpp"

namespace rsca::domain {
namespace {

using control::Json;
using control::Status;

// Where configure/query go: the named component, or else the assembly controller (SCA).
CallResult<const ComponentInstance *> target_of(const Application &app,
                                                const std::string &component) {
  for (const auto &c : app.components) {
    if (!(component.empty() ? c.assembly_controller : c.id == component))
      continue;
    if (c.state == ComponentState::Exited)
      return control::call_error(
          Status::Failed, fmt::format("component {} of application {} has exited", c.id, app.name));
    if (c.state == ComponentState::Unreachable)
      return control::call_error(
          Status::Unavailable,
          fmt::format("component {} of application {} is unreachable: its node {} is lost", c.id,
                      app.name, c.node));
    return &c;
  }
  return control::call_error(
      Status::NotFound,
      fmt::format("application {} has no component {}", app.name,
                  component.empty() ? "(assembly controller)" : excerpt(component)));
}

// `why` a process exited and the last lines of its log, each indented under it.
std::string with_log_tail(const std::string &why, const std::string &tail) {
  std::string out = fmt::format("{}; the last lines of its log (`rsca logs --failed` after a "
                                "failed launch shows it whole):",
                                why);
  std::size_t at = 0;
  while (at < tail.size()) {
    auto nl = tail.find('\n', at);
    if (nl == std::string::npos)
      nl = tail.size();
    out += fmt::format("\n    {}", std::string_view(tail).substr(at, nl - at));
    at = nl + 1;
  }
  return out;
}

using TextValues = std::map<std::string, Json>;

// Property values given as text (from the CLI), typed against the component's PRF.
CallResult<Json> typed_values(const Application &app, const ComponentInstance &component,
                              const TextValues &values) {
  const profile::ComponentPlacement *placement = nullptr;
  app.profile->sad->find_instantiation(component.id, &placement);
  const auto *pkg = placement != nullptr ? app.profile->softpkg_of(*placement) : nullptr;
  Json typed = Json::object();
  for (const auto &[id, text] : values) {
    const auto *definition = pkg != nullptr ? pkg->find_property(id) : nullptr;
    if (definition == nullptr)
      return control::call_error(Status::NotFound, fmt::format("component {} has no property {}",
                                                               component.id, excerpt(id)));
    const std::string value = text.is_string() ? text.get<std::string>() : text.dump();
    profile::PropertyRef ref = profile::SimpleRef{id, value, {}};
    if (std::holds_alternative<profile::SimpleSequenceProperty>(*definition)) {
      profile::SimpleSequenceRef seq{id, {}, {}};
      std::stringstream items(value);
      for (std::string item; std::getline(items, item, ',');)
        seq.values.push_back(item);
      ref = seq;
    }
    auto bound = profile::bind_property(*definition, ref);
    if (!bound)
      return control::call_error(Status::BadRequest, bound.error());
    typed[id] = profile::to_json(*bound);
  }
  return typed;
}

// Values given as text, for a device (whose PRF the domain does not hold): booleans and numbers
// as such, the rest as text.
Json json_values(const TextValues &values) {
  Json out = Json::object();
  for (const auto &[id, v] : values) {
    const std::string text = v.is_string() ? v.get<std::string>() : v.dump();
    const auto parsed = protocol::parse_json(text);
    out[id] = parsed && (parsed->is_boolean() || parsed->is_number()) ? *parsed : Json(text);
  }
  return out;
}

// The running application a configure or query names ("app") and its component that the
// request goes to ("component", else the assembly controller): copies.
struct Target {
  Application app;
  ComponentInstance component;
};

CallResult<Target> target_in(ApplicationRegistry &applications, const app_ops::Target &request) {
  if (!request.app)
    return control::call_error(Status::BadRequest, "the request names no \"app\" (or \"device\")");
  const std::string &name = *request.app;
  auto app = applications.snapshot(name);
  if (!app)
    return control::call_error(Status::NotFound,
                               fmt::format("no application {} is running", excerpt(name)));
  auto target = target_of(*app, request.component.value_or(""));
  if (!target)
    return tl::unexpected(target.error());
  return Target{*app, **target};
}

} // namespace

CallResult<protocol::Empty> DomainManager::Impl::configure(const app_ops::ConfigureRequest &r) {
  const TextValues none;
  if (r.device) {
    auto address = device_address(*r.device);
    if (!address)
      return tl::unexpected(address.error());
    return configure_at(*address, json_values(r.values.value_or(none)));
  }
  auto target = target_in(applications, r);
  if (!target)
    return tl::unexpected(target.error());
  Json properties(r.properties.value_or(none));
  if (r.values) {
    auto typed = typed_values(target->app, target->component, *r.values);
    if (!typed)
      return tl::unexpected(typed.error());
    properties.update(*typed);
  }
  return configure_at(target->component.address, std::move(properties));
}

CallResult<protocol::Empty> DomainManager::Impl::configure_at(const std::string &address,
                                                              Json properties) {
  return control::call<protocol::component::Configure>(*endpoint, address, {std::move(properties)},
                                                       options.call_timeout);
}

CallResult<protocol::component::QueryReply>
DomainManager::Impl::query_at(const std::string &address, std::vector<std::string> ids) {
  return control::call<protocol::component::Query>(*endpoint, address, {std::move(ids)},
                                                   options.call_timeout);
}

CallResult<protocol::component::QueryReply>
DomainManager::Impl::query(const app_ops::QueryRequest &r) {
  if (r.device) {
    auto address = device_address(*r.device);
    if (!address)
      return tl::unexpected(address.error());
    return query_at(*address, r.ids);
  }
  auto target = target_in(applications, r);
  if (!target)
    return tl::unexpected(target.error());
  return query_at(target->component.address, r.ids);
}

CallResult<protocol::Empty>
DomainManager::Impl::component_exited(const protocol::domain::ComponentExitedReport &r) {
  // Every component the process served: one, or those of a component host.
  const std::string why = r.status.empty() ? std::string("exited") : r.status;
  // A launch waiting for it fails with its last words: mostly why it exited.
  const std::string told = r.log_tail.empty() ? why : with_log_tail(why, r.log_tail);
  for (const auto &address : r.addresses) {
    components.exited(address, told); // a launch waiting for it fails at once
    endpoint->abandon(address, why);
  }
  mark_exited(
      [&r](const ComponentInstance &c) {
        return std::find(r.addresses.begin(), r.addresses.end(), c.address) != r.addresses.end();
      },
      why);
  return protocol::Empty{};
}

void DomainManager::Impl::mark_exited(const std::function<bool(const ComponentInstance &)> &which,
                                      const std::string &why) {
  applications.update_all([&](Application &app) {
    for (auto &c : app.components) {
      if (c.pid == 0 || c.state == ComponentState::Exited || !which(c))
        continue;
      components.exited(c.address, why);
      c.state = ComponentState::Exited;
      spdlog::warn("component {} of application {} exited unexpectedly: {}; the application is "
                   "degraded",
                   c.id, app.name, why);
      events->publish(
          "component.exited",
          {{"application", app.name}, {"component", c.id}, {"node", c.node}, {"why", why}});
    }
  });
}

// A component saw its writer miss a connection's deadline or lose liveliness.
CallResult<protocol::Empty>
DomainManager::Impl::connection_problem(const protocol::domain::ConnectionProblemReport &r) {
  spdlog::warn("connection {} of application {} ({}): {} ({} times)", excerpt(r.connection),
               excerpt(r.application), excerpt(r.component), excerpt(r.problem), r.count);
  events->publish("connection.problem", protocol::encode(r));
  return protocol::Empty{};
}

} // namespace rsca::domain
