// The DomainManager's configure and query of properties: of a device, of one component of an
// application, or of an application as a whole, where an id is first one of the SAD's external
// properties (SCA's externalproperties: the id the application gives a component's property)
// and else a property of the assembly controller.
#include <algorithm>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/names.hpp"
#include "control/operation.hpp"
#include "domain/domain_manager_impl.hpp"
#include "profile/property_arguments.hpp"
#include "profile/property_binding.hpp"
#include "profile/property_json.hpp"
#include "protocol/component_ops.hpp"
#include "protocol/json_text.hpp"

namespace rsca::domain {
namespace {

using control::Json;
using control::Status;

// The named component, or else the assembly controller (SCA), if it can be called.
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

// A property id as a request names it, and where it is: a component (empty: the assembly
// controller) and the property's id there.
struct Place {
  std::string id;
  std::string component;
  std::string property;
  bool external = false;
};

// Where `id` is when the request names no component: an external property first.
Place place_of(const Application &app, const std::string &id) {
  for (const auto &p : app.profile->sad->external_properties)
    if (p.external_id == id)
      return {id, p.component_ref, p.property_id, true};
  return {id, "", id, false};
}

// `given` for the property at `place` of `component`, typed against its PRF: as text (`values`:
// the CLI's argument syntax, profile/property_arguments.hpp, or "json:" and JSON), else as the
// JSON it is (`properties`).
CallResult<Json> typed_value(const Application &app, const ComponentInstance &component,
                             const Place &place, const Json &given, bool text) {
  const profile::ComponentPlacement *placement = nullptr;
  app.profile->sad->find_instantiation(component.id, &placement);
  const auto *pkg = placement != nullptr ? app.profile->softpkg_of(*placement) : nullptr;
  const auto *definition = pkg != nullptr ? pkg->find_property(place.property) : nullptr;
  if (definition == nullptr)
    return control::call_error(
        Status::NotFound,
        place.external || !place.component.empty()
            ? fmt::format("component {} has no property {}", component.id, excerpt(place.property))
            : fmt::format("application {} has no external property {} and its assembly "
                          "controller {} no property {}",
                          app.name, excerpt(place.id), component.id, excerpt(place.id)));
  Json json = given;
  if (text && given.is_string() && given.get<std::string>().starts_with("json:")) {
    auto parsed = protocol::parse_json(given.get<std::string>().substr(5));
    if (!parsed)
      return control::call_error(
          Status::BadRequest, fmt::format("property \"{}\": json: {}", place.id, parsed.error()));
    json = std::move(*parsed);
  } else if (text && given.is_string()) {
    auto ref = profile::ref_from_argument(*definition, given.get<std::string>());
    if (!ref)
      return control::call_error(Status::BadRequest, ref.error());
    auto bound = profile::bind_property(*definition, *ref);
    if (!bound)
      return control::call_error(Status::BadRequest, bound.error());
    return profile::to_json(*bound);
  }
  auto value = profile::from_json(*definition, json);
  if (!value)
    return control::call_error(Status::BadRequest, value.error());
  return profile::to_json(*value);
}

// Values given as text, for a device (whose PRF the domain does not hold): booleans and numbers
// as such, the rest as text.
Json json_value(const Json &given) {
  const std::string text = given.is_string() ? given.get<std::string>() : given.dump();
  const auto parsed = protocol::parse_json(text);
  return parsed && (parsed->is_boolean() || parsed->is_number()) ? *parsed : Json(text);
}

// One configure of one component: its properties, typed, and what the reply says of them.
struct Batch {
  const ComponentInstance *component = nullptr;
  Json properties = Json::object();
  std::vector<app_ops::ConfiguredProperty> set;
};

// The values of a configure (typed ones, then text ones over them) by the component they go to,
// each typed against its PRF; nothing is sent unless every one is valid.
CallResult<std::vector<Batch>> batches_of(const Application &app,
                                          const app_ops::ConfigureRequest &r) {
  // id -> (value, whether it is text); a text value overrides a typed one.
  std::map<std::string, std::pair<Json, bool>> given;
  for (const auto &[id, value] : r.properties.value_or(std::map<std::string, Json>{}))
    given[id] = {value, false};
  for (const auto &[id, value] : r.values.value_or(std::map<std::string, Json>{}))
    given[id] = {value, true};
  const std::string named = r.component.value_or("");
  std::vector<Batch> batches;
  for (const auto &[id, one] : given) {
    const auto &[value, text] = one;
    const Place place = named.empty() ? place_of(app, id) : Place{id, named, id, false};
    auto component = target_of(app, place.component);
    if (!component)
      return tl::unexpected(component.error());
    auto typed = typed_value(app, **component, place, value, text);
    if (!typed)
      return tl::unexpected(typed.error());
    auto batch = std::find_if(batches.begin(), batches.end(),
                              [&](const Batch &b) { return b.component == *component; });
    if (batch == batches.end())
      batch = batches.insert(batches.end(), Batch{*component, Json::object(), {}});
    batch->properties[place.property] = *typed;
    batch->set.push_back({id, (*component)->id, place.property, *typed});
  }
  return batches;
}

CallResult<Application> running(ApplicationRegistry &applications, const app_ops::Target &request) {
  if (!request.app)
    return control::call_error(Status::BadRequest, "the request names no \"app\" (or \"device\")");
  auto app = applications.snapshot(*request.app);
  if (!app)
    return control::call_error(Status::NotFound,
                               fmt::format("no application {} is running", excerpt(*request.app)));
  return std::move(*app);
}

} // namespace

CallResult<app_ops::ConfigureReply>
DomainManager::Impl::configure(const app_ops::ConfigureRequest &r) {
  app_ops::ConfigureReply reply;
  if (r.device) {
    auto address = device_address(*r.device);
    if (!address)
      return tl::unexpected(address.error());
    Json properties = Json::object();
    for (const auto &[id, value] : r.values.value_or(std::map<std::string, Json>{})) {
      properties[id] = json_value(value);
      reply.set.push_back({id, "", id, properties[id]});
    }
    if (auto done = configure_at(*address, std::move(properties)); !done)
      return tl::unexpected(done.error());
    return reply;
  }
  auto app = running(applications, r);
  if (!app)
    return tl::unexpected(app.error());
  auto batches = batches_of(*app, r);
  if (!batches)
    return tl::unexpected(batches.error());
  for (auto &batch : *batches) {
    if (auto done = configure_at(batch.component->address, std::move(batch.properties)); !done) {
      auto error = done.error();
      if (!reply.set.empty()) // the components before it keep what they took
        error.message += fmt::format("; {} of {} was configured before", reply.set.front().id,
                                     reply.set.front().component);
      return tl::unexpected(error);
    }
    for (auto &one : batch.set) {
      spdlog::info("configured {} of application {}: {} ({}:{})", one.id, app->name,
                   one.value.dump(), one.component, one.property);
      reply.set.push_back(std::move(one));
    }
  }
  return reply;
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
  auto app = running(applications, r);
  if (!app)
    return tl::unexpected(app.error());
  const std::string named = r.component.value_or("");
  if (!named.empty()) {
    auto component = target_of(*app, named);
    if (!component)
      return tl::unexpected(component.error());
    return query_at((*component)->address, r.ids);
  }
  return query_application(*app, r.ids);
}

// An application's properties: those `ids` name (external ones first), or else its assembly
// controller's and every external one, each under the id the request knows it by.
CallResult<protocol::component::QueryReply>
DomainManager::Impl::query_application(const Application &app,
                                       const std::vector<std::string> &ids) {
  std::vector<Place> places;
  if (ids.empty()) {
    places.push_back({"", "", "", false}); // the assembly controller's every property
    for (const auto &p : app.profile->sad->external_properties)
      places.push_back({p.external_id, p.component_ref, p.property_id, true});
  }
  for (const auto &id : ids)
    places.push_back(place_of(app, id));
  protocol::component::QueryReply reply;
  for (const auto &place : places) {
    auto component = target_of(app, place.component);
    if (!component)
      return tl::unexpected(component.error());
    std::vector<std::string> one;
    if (!place.property.empty())
      one.push_back(place.property);
    auto answered = query_at((*component)->address, std::move(one));
    if (!answered)
      return tl::unexpected(answered.error());
    if (place.property.empty())
      reply.properties.update(answered->properties);
    else if (answered->properties.contains(place.property))
      reply.properties[place.id] = answered->properties.at(place.property);
  }
  return reply;
}

} // namespace rsca::domain
