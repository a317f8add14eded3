#include "domain/connection_manager.hpp"

#include <cctype>
#include <future>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/dds_names.hpp"
#include "dds/port_qos.hpp"

namespace rsca::domain {
namespace {

using control::CallResult;
using control::Json;
using control::Status;

} // namespace

// The control address of the port's component, with the port's type; an error naming the end.
CallResult<std::string> ConnectionManager::address_and_repid(const PortRef &ref, bool uses,
                                                             std::string &repid) const {
  auto app = find_(ref.application);
  if (!app)
    return control::call_error(Status::NotFound,
                               fmt::format("no application {} runs", ref.application));
  const auto *component = app->find_component(ref.component);
  if (component == nullptr)
    return control::call_error(Status::NotFound, fmt::format("application {} has no component {}",
                                                             ref.application, ref.component));
  const profile::ComponentPlacement *placement = nullptr;
  app->profile->sad->find_instantiation(ref.component, &placement);
  const auto *pkg = placement != nullptr ? app->profile->softpkg_of(*placement) : nullptr;
  const auto direction = uses ? profile::PortDirection::Uses : profile::PortDirection::Provides;
  const auto *port =
      pkg != nullptr && pkg->scd ? pkg->scd->find_port(ref.port, direction) : nullptr;
  if (port == nullptr)
    return control::call_error(Status::NotFound, fmt::format("{} is not a {} port", ref.to_string(),
                                                             uses ? "uses" : "provides"));
  repid = port->repid;
  return component->address;
}

CallResult<RuntimeConnection> ConnectionManager::connect(const PortRef &uses,
                                                         const PortRef &provides, std::string id,
                                                         const Json &qos_json) {
  std::string uses_repid, provides_repid;
  auto uses_address = address_and_repid(uses, true, uses_repid);
  if (!uses_address)
    return tl::unexpected(uses_address.error());
  auto provides_address = address_and_repid(provides, false, provides_repid);
  if (!provides_address)
    return tl::unexpected(provides_address.error());
  if (uses_repid != provides_repid)
    return control::call_error(
        Status::BadRequest, fmt::format("port type: {} sends {}, but {} takes {}", uses.to_string(),
                                        uses_repid, provides.to_string(), provides_repid));
  auto qos = dds::connection_qos_from_json(qos_json);
  if (!qos)
    return control::call_error(Status::BadRequest, qos.error().to_string());
  RuntimeConnection c{std::move(id), uses, provides, "", uses_repid, dds::qos_to_json(*qos)};
  {
    std::lock_guard lock(mutex_);
    if (c.id.empty())
      c.id = fmt::format("runtime_{}", ++next_);
    if (connections_.count(c.id) != 0)
      return control::call_error(Status::Rejected, fmt::format("a connection {} exists", c.id));
    c.topic = fmt::format("rsca_{}_runtime_{}", dds_name(domain_), dds_name(c.id));
    connections_[c.id] = c; // reserved; removed again on failure
  }
  auto body = [&](const PortRef &end, const char *direction) {
    return Json{{"connection", c.id}, {"port", end.port}, {"direction", direction},
                {"topic", c.topic},   {"repid", c.repid}, {"qos", c.qos}};
  };
  // The reader first, so that the first samples written find it.
  auto provided = endpoint_->call_sync(*provides_address, "component.connect",
                                       body(provides, "provides"), timeout_);
  auto used = provided ? endpoint_->call_sync(*uses_address, "component.connect",
                                              body(uses, "uses"), timeout_)
                       : provided;
  if (!provided || !used) {
    endpoint_->call_sync(*provides_address, "component.disconnect",
                         Json{{"connection", c.id}, {"port", provides.port}}, timeout_);
    std::lock_guard lock(mutex_);
    connections_.erase(c.id);
    const auto &error = !provided ? provided.error() : used.error();
    return control::call_error(error.status, fmt::format("connection {}: {}", c.id, error.message));
  }
  spdlog::info("runtime connection {}: {} -> {} on topic {}", c.id, uses.to_string(),
               provides.to_string(), c.topic);
  return c;
}

CallResult<void> ConnectionManager::disconnect(const std::string &id) {
  RuntimeConnection c;
  {
    std::lock_guard lock(mutex_);
    auto it = connections_.find(id);
    if (it == connections_.end())
      return control::call_error(Status::NotFound, fmt::format("no runtime connection {}", id));
    c = it->second;
    connections_.erase(it);
  }
  for (const auto *end : {&c.uses, &c.provides}) {
    std::string repid;
    auto address = address_and_repid(*end, end == &c.uses, repid);
    if (address)
      endpoint_->call_sync(*address, "component.disconnect",
                           Json{{"connection", c.id}, {"port", end->port}}, timeout_);
  }
  spdlog::info("runtime connection {} removed", id);
  return {};
}

void ConnectionManager::application_released(const std::string &application) {
  std::vector<std::string> ids;
  {
    std::lock_guard lock(mutex_);
    for (const auto &[id, c] : connections_)
      if (c.uses.application == application || c.provides.application == application)
        ids.push_back(id);
  }
  for (const auto &id : ids)
    disconnect(id); // the released application's own end is going anyway
}

std::vector<RuntimeConnection> ConnectionManager::list() const {
  std::lock_guard lock(mutex_);
  std::vector<RuntimeConnection> out;
  for (const auto &[id, c] : connections_)
    out.push_back(c);
  return out;
}

nlohmann::json to_json(const RuntimeConnection &c) {
  return {{"id", c.id},       {"uses", c.uses.to_string()}, {"provides", c.provides.to_string()},
          {"topic", c.topic}, {"repid", c.repid},           {"qos", c.qos}};
}

} // namespace rsca::domain
