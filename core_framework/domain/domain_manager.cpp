#include "domain/domain_manager.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <fstream>
#include <functional>
#include <future>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "allocator/plan_json.hpp"
#include "common/elapsed.hpp"
#include "control/domain_events.hpp"
#include "domain/connection_manager.hpp"
#include "domain/launch_tracker.hpp"
#include "profile/profile_loader.hpp"
#include "profile/property_binding.hpp"
#include "profile/property_json.hpp"
#include "profile/runtime_model.hpp"

namespace rsca::domain {
namespace {

namespace fs = std::filesystem;
using control::CallResult;
using control::Json;
using control::Status;

struct InstalledApplication {
  std::string name;
  fs::path sad;
  std::shared_ptr<const profile::ResolvedApplication> profile;
};

struct NodeRecord {
  std::string name;
  std::string address;
  Json body;
};

Json steps_json(const std::vector<LaunchStep> &steps) {
  Json out = Json::array();
  for (const auto &s : steps)
    out.push_back({{"step", s.step}, {"detail", s.detail}, {"ms", s.milliseconds}});
  return out;
}

template <typename T>
CallResult<T> required(const Json &body, const char *key) {
  if (!body.contains(key))
    return control::call_error(Status::BadRequest, fmt::format("the request has no \"{}\"", key));
  try {
    return body.at(key).get<T>();
  } catch (const Json::exception &) {
    return control::call_error(Status::BadRequest, fmt::format("\"{}\" has the wrong type", key));
  }
}

// A path from a client must stay inside the repository: no absolute paths, no "..".
std::optional<fs::path> safe_relative(const std::string &path) {
  fs::path p = fs::path(path).lexically_normal();
  if (p.empty() || p.is_absolute() || *p.begin() == "..")
    return std::nullopt;
  return p;
}

// One end's live state from its owner's status (by address): {"matched", "samples",
// "filtered"}, or null.
Json end_state(const std::map<std::string, Json> &status_of, const std::string &address,
               const std::string &port_name, const std::string &connection) {
  auto it = status_of.find(address);
  if (address.empty() || it == status_of.end())
    return nullptr;
  for (const auto &port : it->second.value("ports", Json::array())) {
    if (port.value("name", "") != port_name)
      continue;
    for (const auto &c : port.value("connections", Json::array())) {
      if (c.value("connection", "") != connection)
        continue;
      if (c.contains("calls"))
        return Json{{"calls", c.value("calls", 0)}}; // a caller of a supported interface
      return Json{{"matched", c.value("matched", 0)},
                  {"samples", c.value("samples", 0)},
                  {"filtered", c.value("filtered", 0)},
                  {"deadline_missed", c.value("deadline_missed", 0)},
                  {"in_host", c.value("in_host", false)}};
    }
  }
  return nullptr;
}

Json connection_json(const Application &app, const ConnectionInstance &c,
                     const std::map<std::string, Json> &status_of) {
  auto state = [&](const ConnectionEnd &e) {
    return end_state(status_of, e.address, e.port, end_key(c, e));
  };
  return {{"application", app.name},
          {"id", c.id},
          {"uses", c.uses.name()},
          {"provides", c.provides.name()},
          {"topic", c.topic},
          {"repid", c.repid},
          {"qos", c.qos},
          {"filter", c.filter},
          {"uses_state", state(c.uses)},
          {"provides_state", state(c.provides)}};
}

Json device_ids(const Json &node_body) {
  Json ids = Json::array();
  for (const auto &d : node_body.value("devices", Json::array()))
    ids.push_back(d.value("id", ""));
  return ids;
}

std::vector<allocator::Device> devices_of(const std::string &node, const Json &body) {
  std::vector<allocator::Device> devices;
  for (const auto &d : body.value("devices", Json::array()))
    devices.push_back(allocator::device_from_announcement(node, d));
  return devices;
}

// The assignments and strategy a launch or plan request gives.
CallResult<std::pair<std::map<std::string, std::string>, std::optional<allocator::Strategy>>>
placement_options(const Json &body) {
  std::map<std::string, std::string> assignments;
  const Json assign = body.value("assign", Json::object());
  for (const auto &[k, v] : assign.items())
    assignments[k] = v.get<std::string>();
  std::optional<allocator::Strategy> strategy;
  if (body.contains("strategy")) {
    strategy = allocator::parse_strategy(body.value("strategy", ""));
    if (!strategy)
      return control::call_error(Status::BadRequest,
                                 fmt::format("unknown placement strategy \"{}\": pack or spread",
                                             body.value("strategy", "")));
  }
  return std::pair{assignments, strategy};
}

} // namespace

struct DomainManager::Impl {
  DomainOptions options;
  std::shared_ptr<dds::Participant> participant;
  std::unique_ptr<control::Endpoint> endpoint;
  allocator::ResourceAllocator allocator;
  ComponentRegistry components;
  std::unique_ptr<control::DomainEvents> events;
  std::optional<ConnectionManager> runtime_connections; // made before the endpoint opens
  std::optional<EventChannelManager> channels;          // made when the domain's name is known
  std::optional<DomainStore> store;
  std::mutex kept_connections; // a runtime connection and its record in the store change together

  std::mutex mutex; // guards everything below
  std::map<std::string, NodeRecord> nodes;
  std::map<std::string, InstalledApplication> installed;
  std::map<std::string, std::shared_ptr<Application>> applications;
  LaunchTracker launches;
  std::atomic<std::uint64_t> launch_counter{0};

  ApplicationFactory factory() {
    DomainServices s;
    s.domain_name = options.name;
    s.endpoint = endpoint.get();
    s.allocator = &allocator;
    s.components = &components;
    s.channels = &*channels;
    s.node_address = [this](const std::string &node) -> std::optional<std::string> {
      std::lock_guard lock(mutex);
      auto it = nodes.find(node);
      if (it == nodes.end())
        return std::nullopt;
      return it->second.address;
    };
    s.device_ports = [this](const std::string &id) -> std::optional<DevicePorts> {
      std::lock_guard lock(mutex);
      const Json *device = find_device(id);
      if (device == nullptr || !device->contains("address"))
        return std::nullopt;
      return DevicePorts{device->value("address", ""), device->value("ports", Json::array())};
    };
    s.next_launch = [this] { return ++launch_counter; };
    s.call_timeout = options.call_timeout;
    s.registration_timeout = options.registration_timeout;
    s.strategy = options.strategy;
    return ApplicationFactory(std::move(s));
  }

  // A device as its node announced it; null when its node has not registered or has no such
  // device. Called with `mutex` held.
  const Json *find_device(const std::string &id) const;
  CallResult<std::string> device_address(const std::string &id);
  CallResult<ResolvedEnd> resolve_end(const PortRef &ref, profile::PortDirection direction);
  CallResult<ResolvedEnd> resolve_component_end(const PortRef &ref,
                                                profile::PortDirection direction);
  CallResult<ResolvedEnd> resolve_device_end(const PortRef &ref, profile::PortDirection direction);
  void serve();
  void on_announcement(const control::AnnouncementEvent &event);
  Expected<void> load_installed();
  CallResult<Json> install(const Json &body);
  void write_runtime_models(const profile::ResolvedApplication &app);
  CallResult<Json> uninstall(const Json &body);
  CallResult<Json> list_installed();
  CallResult<Json> create_application(const Json &body);
  CallResult<Json> progress(const Json &body);
  CallResult<Json> cancel_launch(const Json &body);
  CallResult<std::shared_ptr<Application>> find_application(const Json &body);
  CallResult<Json> release(const Json &body);
  CallResult<Json> configure(const Json &body);
  CallResult<Json> query(const Json &body);
  CallResult<Json> list_nodes();
  CallResult<Json> list_devices();
  CallResult<Json> plan_application(const Json &body);
  CallResult<Json> list_channels();
  CallResult<Json> create_channel(const Json &body);
  CallResult<Json> destroy_channel(const Json &body);
  CallResult<Json> list_connections(const Json &body);
  CallResult<Json> create_connection(const Json &body);
  Json runtime_end_state(const ResolvedEnd &end, const std::string &connection);
  CallResult<Json> destroy_connection(const Json &body);
  CallResult<RuntimeConnection> make_connection(const Json &body);
  void restore_connections();
  CallResult<Json> component_exited(const Json &body);
  // Marks the running components `which` selects as exited (the caller holds `mutex`).
  void mark_exited(const std::function<bool(const ComponentInstance &)> &which,
                   const std::string &why);
  CallResult<Json> connection_problem(const Json &body);
  std::string unique_name(const std::string &wanted) const;
  CallResult<std::string> target_of(const Application &app, const Json &body) const;
};

Expected<void> DomainManager::Impl::load_installed() {
  auto records = store->installed();
  if (!records)
    return tl::unexpected(records.error());
  for (const auto &r : *records) {
    const fs::path sad = options.repository / r.sad;
    profile::ProfileLoader loader(options.repository / r.name);
    auto app = loader.load_application(sad);
    if (!app) {
      spdlog::warn("installed application {} no longer loads, skipped:\n{}", r.name,
                   app.error().to_string());
      continue;
    }
    write_runtime_models(*app); // anew: the files may have changed while the domain was down
    installed[r.name] = {r.name, sad,
                         std::make_shared<const profile::ResolvedApplication>(std::move(*app))};
  }
  spdlog::info("{} installed application(s) loaded", installed.size());
  return {};
}

// The application's components then start from their runtime models, without reading XML; a
// component without one still starts, reading its profile (profile/runtime_model.hpp).
void DomainManager::Impl::write_runtime_models(const profile::ResolvedApplication &app) {
  for (const auto &[id, softpkg] : app.component_files)
    if (auto ok = profile::write_runtime_model(*softpkg); !ok)
      spdlog::warn("no runtime model for {}: {}", softpkg->spd_path.string(),
                   ok.error().to_string());
}

CallResult<Json> DomainManager::Impl::install(const Json &body) {
  auto sad_rel = required<std::string>(body, "sad");
  auto files = required<std::vector<Json>>(body, "files");
  if (!sad_rel || !files)
    return tl::unexpected(sad_rel ? files.error() : sad_rel.error());
  // Write into a staging folder, load from there, and only then replace what was installed.
  const std::string staging_name =
      fmt::format(".staging-{}", std::chrono::steady_clock::now().time_since_epoch().count());
  const fs::path staging = options.repository / staging_name;
  std::error_code ec;
  fs::remove_all(staging, ec);
  for (const auto &f : *files) {
    auto rel = safe_relative(f.value("path", ""));
    if (!rel) {
      fs::remove_all(staging, ec);
      return control::call_error(
          Status::BadRequest,
          fmt::format("file path \"{}\" is not inside an SDR root", f.value("path", "")));
    }
    fs::create_directories((staging / *rel).parent_path(), ec);
    std::ofstream(staging / *rel, std::ios::binary) << f.value("content", "");
  }
  auto rel_sad = safe_relative(*sad_rel);
  profile::ProfileLoader loader(staging);
  auto app = rel_sad ? loader.load_application(staging / *rel_sad)
                     : Expected<profile::ResolvedApplication>(
                           make_error({*sad_rel, 0, 0}, "install", "not a relative path"));
  if (!app) {
    fs::remove_all(staging, ec);
    return control::call_error(Status::BadRequest, app.error().to_string());
  }
  const std::string name =
      body.value("name", app->sad->name.empty() ? app->sad->id : app->sad->name);
  std::lock_guard lock(mutex);
  const fs::path final_dir = options.repository / name;
  fs::remove_all(final_dir, ec);
  fs::rename(staging, final_dir, ec);
  if (ec)
    return control::call_error(Status::Failed, fmt::format("storing {}: {}", name, ec.message()));
  profile::ProfileLoader final_loader(final_dir);
  auto final_app = final_loader.load_application(final_dir / *rel_sad);
  if (!final_app)
    return control::call_error(Status::Failed, final_app.error().to_string());
  write_runtime_models(*final_app);
  if (auto ok = store->put_installed({name, (fs::path(name) / *rel_sad).string()}); !ok)
    return control::call_error(Status::Failed, ok.error().to_string());
  installed[name] = {name, final_dir / *rel_sad,
                     std::make_shared<const profile::ResolvedApplication>(std::move(*final_app))};
  spdlog::info("installed application {} ({} files)", name, files->size());
  Json warnings = Json::array();
  for (const auto &w : installed[name].profile->warnings)
    warnings.push_back(to_string(w));
  return Json{{"name", name}, {"warnings", warnings}};
}

CallResult<Json> DomainManager::Impl::uninstall(const Json &body) {
  auto name = required<std::string>(body, "name");
  if (!name)
    return tl::unexpected(name.error());
  std::lock_guard lock(mutex);
  if (installed.erase(*name) == 0)
    return control::call_error(Status::NotFound,
                               fmt::format("no application {} is installed", *name));
  for (const auto &[app_name, app] : applications)
    if (app->installed == *name)
      spdlog::info("{} stays running after uninstalling {}", app_name, *name);
  store->remove_installed(*name);
  std::error_code ec;
  fs::remove_all(options.repository / *name, ec);
  return Json{{"name", *name}};
}

CallResult<Json> DomainManager::Impl::list_installed() {
  std::lock_guard lock(mutex);
  Json list = Json::array();
  for (const auto &[name, app] : installed) {
    std::size_t count = 0;
    for (const auto &p : app.profile->sad->placements)
      count += p.instantiations.size();
    list.push_back({{"name", name}, {"sad", app.sad.string()}, {"components", count}});
  }
  return Json{{"applications", list}};
}

std::string DomainManager::Impl::unique_name(const std::string &wanted) const {
  if (applications.count(wanted) == 0)
    return wanted;
  for (int i = 2;; ++i)
    if (auto name = fmt::format("{}_{}", wanted, i); applications.count(name) == 0)
      return name;
}

CallResult<Json> DomainManager::Impl::create_application(const Json &body) {
  auto installed_name = required<std::string>(body, "application");
  if (!installed_name)
    return tl::unexpected(installed_name.error());
  LaunchRequest request;
  {
    std::lock_guard lock(mutex);
    auto it = installed.find(*installed_name);
    if (it == installed.end())
      return control::call_error(Status::NotFound,
                                 fmt::format("no application {} is installed", *installed_name));
    request.installed = *installed_name;
    request.profile = it->second.profile;
    const std::string wanted = body.value("name", *installed_name);
    if (body.contains("name") && applications.count(wanted) != 0)
      return control::call_error(Status::Rejected,
                                 fmt::format("an application named {} already runs", wanted));
    request.name = unique_name(wanted);
    // Reserve the name while launching.
    applications[request.name] = nullptr;
  }
  auto unreserve = [this, &request] {
    std::lock_guard lock(mutex);
    applications.erase(request.name);
  };
  const std::string launch_id = body.value("launch_id", request.name);
  request.cancelled = launches.begin(launch_id);
  if (!request.cancelled) {
    unreserve();
    spdlog::info("launch {} of {} not begun: its caller cancelled it first", launch_id,
                 request.installed);
    return control::call_error(
        Status::Failed,
        fmt::format("the launch of {} was cancelled before it began", request.installed));
  }
  request.start = body.value("start", true);
  auto placement = placement_options(body);
  if (!placement) {
    unreserve();
    launches.finish(launch_id, false);
    return tl::unexpected(placement.error());
  }
  std::tie(request.assignments, request.strategy) = *placement;
  auto record = [this, &launch_id](const LaunchStep &step) { launches.record(launch_id, step); };
  const auto began = std::chrono::steady_clock::now();
  auto app = factory().create(request, record);
  // Taken before finish: a finished launch may be forgotten.
  const auto recorded = launches.progress(launch_id);
  if (!launches.finish(launch_id, app.has_value())) {
    // Cancelled after its last step: its caller was told it would not run.
    if (auto released = factory().release(**app); !released)
      spdlog::warn("application {} launched as its cancel came; releasing it failed: {}",
                   request.name, released.error().message);
    else
      spdlog::warn("application {} launched as its cancel came; released", request.name);
    app = control::call_error(
        Status::Failed,
        fmt::format("launch of {} cancelled after its last step; released", request.name));
    launches.finish(launch_id, false);
  }
  std::lock_guard lock(mutex);
  if (!app) {
    applications.erase(request.name);
    events->publish(app.error().status == Status::Rejected ? "application.rejected"
                                                           : "application.failed",
                    {{"application", request.name},
                     {"installed", request.installed},
                     {"error", app.error().message}});
    return tl::unexpected(app.error());
  }
  events->publish("application.created", {{"application", request.name},
                                          {"installed", request.installed},
                                          {"components", (*app)->components.size()}});
  applications[request.name] = *app;
  runtime_connections->endpoints_changed(); // connections waiting for it
  Json reply = to_json(**app);
  reply["launch"] = {{"steps", steps_json(recorded ? recorded->steps : std::vector<LaunchStep>{})},
                     {"ms", ms_since(began)}};
  return reply;
}

CallResult<Json> DomainManager::Impl::progress(const Json &body) {
  auto id = required<std::string>(body, "launch_id");
  if (!id)
    return tl::unexpected(id.error());
  auto progress = launches.progress(*id);
  if (!progress)
    return control::call_error(Status::NotFound, fmt::format("no launch {}", *id));
  return Json{{"steps", steps_json(progress->steps)}, {"done", progress->done}};
}

// A caller that stops waiting for its launch (the CLI's own deadline) cancels it, so that no
// application it gave up on appears later: the launch rolls back at its next step, or at once
// when it is waiting for registrations. A cancel that overtook its create is kept: that launch
// never begins.
CallResult<Json> DomainManager::Impl::cancel_launch(const Json &body) {
  auto id = required<std::string>(body, "launch_id");
  if (!id)
    return tl::unexpected(id.error());
  const auto outcome = launches.cancel(*id);
  if (!outcome.cancelled)
    return Json{{"cancelled", false}, {"done", true}};
  if (!outcome.begun) {
    spdlog::info("launch {} cancelled by its caller before it began", *id);
    return Json{{"cancelled", true}, {"done", false}, {"begun", false}};
  }
  spdlog::info("launch {} cancelled by its caller", *id);
  components.interrupt();
  return Json{{"cancelled", true}, {"done", false}, {"begun", true}};
}

CallResult<std::shared_ptr<Application>> DomainManager::Impl::find_application(const Json &body) {
  auto name = required<std::string>(body, "app");
  if (!name)
    return tl::unexpected(name.error());
  std::lock_guard lock(mutex);
  auto it = applications.find(*name);
  if (it == applications.end() || !it->second)
    return control::call_error(Status::NotFound,
                               fmt::format("no application {} is running", *name));
  return it->second;
}

CallResult<Json> DomainManager::Impl::release(const Json &body) {
  auto app = find_application(body);
  if (!app)
    return tl::unexpected(app.error());
  const std::string name = (*app)->name;
  {
    std::lock_guard lock(mutex);
    applications.erase(name);
  }
  // Its runtime connections wait for it again; their other ends are disconnected. Only now that
  // it can no longer be found: a retry of pending connections in between would wire them to it.
  runtime_connections->owner_gone([&name](const PortRef &ref) {
    return ref.kind != PortRef::Kind::Device && ref.owner == name;
  });
  auto unconfirmed = factory().release(**app);
  spdlog::info("application {} released", (*app)->name);
  events->publish("application.released", {{"application", (*app)->name}});
  if (!unconfirmed)
    return control::call_error(
        unconfirmed.error().status,
        fmt::format("released {} with problems: {}", (*app)->name, unconfirmed.error().message));
  return Json{{"name", (*app)->name}, {"unconfirmed", *unconfirmed}};
}

// Where configure/query go: the named component, or else the assembly controller (SCA).
CallResult<std::string> DomainManager::Impl::target_of(const Application &app,
                                                       const Json &body) const {
  const std::string component = body.value("component", "");
  for (const auto &c : app.components)
    if (component.empty() ? c.assembly_controller : c.id == component)
      return c.address;
  return control::call_error(Status::NotFound,
                             fmt::format("application {} has no component {}", app.name,
                                         component.empty() ? "(assembly controller)" : component));
}

namespace {

// Property values given as text (from the CLI), typed against the component's PRF.
CallResult<Json> typed_values(const Application &app, const ComponentInstance &component,
                              const Json &values) {
  const profile::ComponentPlacement *placement = nullptr;
  app.profile->sad->find_instantiation(component.id, &placement);
  const auto *pkg = placement != nullptr ? app.profile->softpkg_of(*placement) : nullptr;
  Json typed = Json::object();
  for (const auto &[id, text] : values.items()) {
    const auto *definition = pkg != nullptr ? pkg->find_property(id) : nullptr;
    if (definition == nullptr)
      return control::call_error(Status::NotFound,
                                 fmt::format("component {} has no property {}", component.id, id));
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
      return control::call_error(Status::BadRequest, bound.error().diagnostics().front().message);
    typed[id] = profile::to_json(*bound);
  }
  return typed;
}

} // namespace

// A device's control address, for "device" requests of app.configure and app.query.
CallResult<std::string> DomainManager::Impl::device_address(const std::string &id) {
  std::lock_guard lock(mutex);
  const Json *device = find_device(id);
  if (device == nullptr)
    return control::call_error(Status::NotFound, fmt::format("no device {} has registered", id));
  if (!device->contains("address"))
    return control::call_error(Status::NotFound,
                               fmt::format("device {} has no properties to reach", id));
  return device->value("address", "");
}

namespace {

// Values given as text, for a device (whose PRF the domain does not hold): booleans and numbers
// as such, the rest as text.
Json json_values(const Json &values) {
  Json out = Json::object();
  for (const auto &[id, v] : values.items()) {
    const std::string text = v.is_string() ? v.get<std::string>() : v.dump();
    const Json parsed = Json::parse(text, nullptr, false);
    out[id] =
        !parsed.is_discarded() && (parsed.is_boolean() || parsed.is_number()) ? parsed : Json(text);
  }
  return out;
}

} // namespace

CallResult<Json> DomainManager::Impl::configure(const Json &body) {
  if (body.contains("device")) {
    auto address = device_address(body.value("device", ""));
    if (!address)
      return tl::unexpected(address.error());
    return endpoint->call_sync(
        *address, "component.configure",
        Json{{"properties", json_values(body.value("values", Json::object()))}},
        options.call_timeout);
  }
  auto app = find_application(body);
  if (!app)
    return tl::unexpected(app.error());
  auto target = target_of(**app, body);
  if (!target)
    return tl::unexpected(target.error());
  Json properties = body.value("properties", Json::object());
  if (body.contains("values")) {
    const ComponentInstance *component = nullptr;
    for (const auto &c : (*app)->components)
      if (c.address == *target)
        component = &c;
    auto typed = typed_values(**app, *component, body.at("values"));
    if (!typed)
      return tl::unexpected(typed.error());
    properties.update(*typed);
  }
  return endpoint->call_sync(*target, "component.configure", Json{{"properties", properties}},
                             options.call_timeout);
}

CallResult<Json> DomainManager::Impl::query(const Json &body) {
  if (body.contains("device")) {
    auto address = device_address(body.value("device", ""));
    if (!address)
      return tl::unexpected(address.error());
    return endpoint->call_sync(*address, "component.query",
                               Json{{"ids", body.value("ids", Json::array())}},
                               options.call_timeout);
  }
  auto app = find_application(body);
  if (!app)
    return tl::unexpected(app.error());
  auto target = target_of(**app, body);
  if (!target)
    return tl::unexpected(target.error());
  return endpoint->call_sync(*target, "component.query",
                             Json{{"ids", body.value("ids", Json::array())}}, options.call_timeout);
}

CallResult<Json> DomainManager::Impl::list_nodes() {
  std::lock_guard lock(mutex);
  Json list = Json::array();
  for (const auto &[name, node] : nodes)
    list.push_back({{"name", name},
                    {"address", node.address},
                    {"pid", node.body.value("pid", 0)},
                    {"devices", node.body.value("devices", Json::array()).size()}});
  return Json{{"nodes", list}};
}

CallResult<Json> DomainManager::Impl::list_devices() {
  return Json{{"devices", allocator::to_json(allocator.snapshot())}};
}

CallResult<Json> DomainManager::Impl::list_channels() {
  Json list = Json::array();
  for (const auto &c : channels->list())
    list.push_back(to_json(c));
  return Json{{"channels", list}};
}

CallResult<Json> DomainManager::Impl::create_channel(const Json &body) {
  auto name = required<std::string>(body, "name");
  if (!name)
    return tl::unexpected(name.error());
  auto channel = channels->create(*name);
  if (!channel)
    return tl::unexpected(channel.error());
  return to_json(*channel);
}

CallResult<Json> DomainManager::Impl::destroy_channel(const Json &body) {
  auto name = required<std::string>(body, "name");
  if (!name)
    return tl::unexpected(name.error());
  if (auto ok = channels->destroy(*name); !ok)
    return tl::unexpected(ok.error());
  return Json{{"name", *name}};
}

// Every connection of the running applications (or of one), with its live state as its
// components report it: matched or not, samples through it.
CallResult<Json> DomainManager::Impl::list_connections(const Json &body) {
  const std::string only = body.value("app", "");
  std::vector<std::shared_ptr<Application>> apps;
  {
    std::lock_guard lock(mutex);
    for (const auto &[name, app] : applications)
      if (app && (only.empty() || name == only))
        apps.push_back(app);
  }
  if (!only.empty() && apps.empty())
    return control::call_error(Status::NotFound, fmt::format("no application {} runs", only));
  Json list = Json::array();
  for (const auto &app : apps) {
    std::set<std::string> addresses;
    for (const auto &c : app->components)
      addresses.insert(c.address);
    for (const auto &c : app->connections)
      for (const auto *end : {&c.uses, &c.provides})
        if (!end->address.empty())
          addresses.insert(end->address); // device ends
    std::vector<control::Call> calls;
    for (const auto &address : addresses)
      calls.push_back({address, "component.status", Json::object()});
    const auto statuses = endpoint->call_all(calls, options.call_timeout);
    std::map<std::string, Json> status_of;
    for (std::size_t i = 0; i < calls.size(); ++i)
      if (statuses[i])
        status_of[calls[i].target] = *statuses[i];
    for (const auto &c : app->connections)
      list.push_back(connection_json(*app, c, status_of));
  }
  for (const auto &c : runtime_connections->list())
    if (only.empty() || c.uses.owner == only || c.provides.owner == only) {
      Json entry = to_json(c);
      entry["application"] = "(runtime)";
      entry["uses_state"] = c.connected() ? runtime_end_state(c.uses_end, c.id) : Json(nullptr);
      entry["provides_state"] =
          c.connected() ? runtime_end_state(c.provides_end, c.id) : Json(nullptr);
      list.push_back(std::move(entry));
    }
  return Json{{"connections", list}};
}

namespace {

// {"application", "component", "port"}, {"application", "port"} (an external port) or
// {"device", "port"}.
CallResult<PortRef> port_ref(const Json &body, const char *key) {
  if (!body.contains(key) || !body.at(key).is_object())
    return control::call_error(Status::BadRequest,
                               fmt::format("the request has no \"{}\" port", key));
  const Json &end = body.at(key);
  PortRef ref;
  ref.port = end.value("port", "");
  if (end.contains("device")) {
    ref.kind = PortRef::Kind::Device;
    ref.owner = end.value("device", "");
  } else {
    ref.owner = end.value("application", "");
    ref.component = end.value("component", "");
    ref.kind = ref.component.empty() ? PortRef::Kind::External : PortRef::Kind::Component;
  }
  if (ref.owner.empty() || ref.port.empty())
    return control::call_error(
        Status::BadRequest,
        fmt::format("\"{}\" needs a port and an application (with a component) or a device", key));
  return ref;
}

} // namespace

const Json *DomainManager::Impl::find_device(const std::string &id) const {
  const auto colon = id.find(':');
  auto node = nodes.find(id.substr(0, colon));
  if (colon == std::string::npos || node == nodes.end())
    return nullptr;
  const Json &body = node->second.body;
  auto devices = body.find("devices"); // a reference into the record: value() would copy
  if (devices == body.end() || !devices->is_array())
    return nullptr;
  for (const auto &d : *devices)
    if (d.value("id", "") == id)
      return &d;
  return nullptr;
}

CallResult<ResolvedEnd> DomainManager::Impl::resolve_end(const PortRef &ref,
                                                         profile::PortDirection direction) {
  return ref.kind == PortRef::Kind::Device ? resolve_device_end(ref, direction)
                                           : resolve_component_end(ref, direction);
}

CallResult<ResolvedEnd>
DomainManager::Impl::resolve_component_end(const PortRef &ref, profile::PortDirection direction) {
  const bool uses = direction == profile::PortDirection::Uses;
  std::lock_guard lock(mutex);
  auto it = applications.find(ref.owner);
  if (it == applications.end() || !it->second)
    return control::call_error(Status::Unavailable,
                               fmt::format("application {} is not running", ref.owner));
  const Application &app = *it->second;
  std::string component = ref.component, port = ref.port;
  if (ref.kind == PortRef::Kind::External) {
    const auto wanted =
        uses ? profile::ExternalPort::Kind::Uses : profile::ExternalPort::Kind::Provides;
    const profile::ExternalPort *external = nullptr;
    for (const auto &e : app.profile->sad->external_ports)
      if (e.external_name == ref.port && e.kind == wanted)
        external = &e;
    if (external == nullptr)
      return control::call_error(Status::NotFound,
                                 fmt::format("{} is not an external {} port", ref.to_string(),
                                             profile::to_string(direction)));
    component = external->component_ref;
    port = external->port;
  }
  const auto *instance = app.find_component(component);
  if (instance == nullptr)
    return control::call_error(
        Status::NotFound, fmt::format("application {} has no component {}", ref.owner, component));
  const profile::ComponentPlacement *placement = nullptr;
  app.profile->sad->find_instantiation(component, &placement);
  const auto *pkg = placement != nullptr ? app.profile->softpkg_of(*placement) : nullptr;
  const auto *definition =
      pkg != nullptr && pkg->scd ? pkg->scd->find_port(port, direction) : nullptr;
  if (definition == nullptr)
    return control::call_error(Status::NotFound, fmt::format("{} is not a {} port", ref.to_string(),
                                                             profile::to_string(direction)));
  return ResolvedEnd{instance->address, port, definition->repid};
}

CallResult<ResolvedEnd> DomainManager::Impl::resolve_device_end(const PortRef &ref,
                                                                profile::PortDirection direction) {
  const auto wanted = profile::to_string(direction);
  std::lock_guard lock(mutex);
  const std::string node = ref.owner.substr(0, ref.owner.find(':'));
  if (nodes.count(node) == 0)
    return control::call_error(Status::Unavailable,
                               fmt::format("device {} has not registered", ref.owner));
  const Json *device = find_device(ref.owner);
  if (device == nullptr)
    return control::call_error(Status::NotFound,
                               fmt::format("node {} has no device {}", node, ref.owner));
  for (const auto &p : device->value("ports", Json::array()))
    if (p.value("name", "") == ref.port && p.value("direction", "") == wanted)
      return ResolvedEnd{device->value("address", ""), ref.port, p.value("repid", "")};
  return control::call_error(Status::NotFound,
                             fmt::format("{} is not a {} port", ref.to_string(), wanted));
}

// A runtime connection's end as its owner reports it.
Json DomainManager::Impl::runtime_end_state(const ResolvedEnd &end, const std::string &connection) {
  auto status =
      endpoint->call_sync(end.address, "component.status", Json::object(), options.call_timeout);
  if (!status)
    return nullptr;
  return end_state({{end.address, *status}}, end.address, end.port, connection);
}

CallResult<RuntimeConnection> DomainManager::Impl::make_connection(const Json &body) {
  auto uses = port_ref(body, "uses");
  if (!uses)
    return tl::unexpected(uses.error());
  auto provides = port_ref(body, "provides");
  if (!provides)
    return tl::unexpected(provides.error());
  return runtime_connections->connect(*uses, *provides, body.value("id", ""),
                                      body.value("qos", Json::object()));
}

// A runtime connection lasts until `rsca disconnect`, also over a restart of the domain daemon:
// it is kept in the domain's store as its request.
CallResult<Json> DomainManager::Impl::create_connection(const Json &body) {
  // Made and kept as one step, so that a disconnect of the same id cannot come in between.
  std::lock_guard kept_lock(kept_connections);
  auto made = make_connection(body);
  if (!made)
    return tl::unexpected(made.error());
  // The request as given (the QoS asked for, not today's defaults), with the id it got.
  const Json request{{"format", 1},
                     {"id", made->id},
                     {"uses", body.at("uses")},
                     {"provides", body.at("provides")},
                     {"qos", body.value("qos", Json::object())}};
  Json reply = to_json(*made);
  reply["persisted"] = true;
  if (auto kept = store->put_connection({made->id, request.dump()}); !kept) {
    spdlog::warn("runtime connection {} will not outlast a restart of the domain daemon: {}",
                 made->id, kept.error().to_string());
    reply["persisted"] = false;
  }
  return reply;
}

// The runtime connections of before a restart, made again: pending until their ends appear.
void DomainManager::Impl::restore_connections() {
  auto records = store->connections();
  if (!records) {
    spdlog::warn("runtime connections not restored: {}", records.error().to_string());
    return;
  }
  for (const auto &r : *records) {
    const Json request = Json::parse(r.request, nullptr, /*allow_exceptions=*/false);
    auto made = !request.is_object() ? control::call_error(Status::BadRequest, "not JSON")
                : request.value("format", 0) != 1
                    ? control::call_error(Status::BadRequest, "kept in another format")
                    : make_connection(request);
    if (!made) {
      spdlog::warn("runtime connection {} not restored ({}); `rsca disconnect {}` forgets it", r.id,
                   made.error().message, r.id);
      continue;
    }
    spdlog::info("runtime connection {} restored: {} -> {}{}", r.id, made->uses.to_string(),
                 made->provides.to_string(), made->connected() ? "" : " (pending)");
  }
}

CallResult<Json> DomainManager::Impl::destroy_connection(const Json &body) {
  auto id = required<std::string>(body, "id");
  if (!id)
    return tl::unexpected(id.error());
  std::lock_guard kept_lock(kept_connections);
  // Forgotten also when not made now: a kept request that no longer restores is removed so.
  auto forgotten = store->remove_connection(*id);
  if (!forgotten)
    spdlog::warn("runtime connection {}: it may come back after a restart of the domain daemon: "
                 "{}",
                 *id, forgotten.error().to_string());
  if (auto ok = runtime_connections->disconnect(*id); !ok)
    return tl::unexpected(ok.error());
  return Json{{"id", *id}};
}

// Admission and placement of an installed application on the domain as it is, reserving nothing.
CallResult<Json> DomainManager::Impl::plan_application(const Json &body) {
  auto name = required<std::string>(body, "application");
  if (!name)
    return tl::unexpected(name.error());
  auto placement = placement_options(body);
  if (!placement)
    return tl::unexpected(placement.error());
  std::shared_ptr<const profile::ResolvedApplication> profile;
  {
    std::lock_guard lock(mutex);
    auto it = installed.find(*name);
    if (it == installed.end())
      return control::call_error(Status::NotFound,
                                 fmt::format("no application {} is installed", *name));
    profile = it->second.profile;
  }
  const allocator::PlanOptions plan_options{placement->second.value_or(options.strategy)};
  auto plan = allocator.plan(allocator::plan_request_of(*profile, placement->first), plan_options);
  const std::string strategy(to_string(plan_options.strategy));
  if (!plan)
    return Json{{"admitted", false},
                {"rejections", allocator::to_json(plan.error())},
                {"strategy", strategy}};
  return Json{{"admitted", true}, {"plan", allocator::to_json(*plan)}, {"strategy", strategy}};
}

CallResult<Json> DomainManager::Impl::component_exited(const Json &body) {
  // Every component the process served: one, or those of a component host.
  const auto addresses = body.value("addresses", std::vector<std::string>{});
  const std::string why = body.value("status", "exited");
  for (const auto &address : addresses) {
    components.exited(address, why); // a launch waiting for it fails at once
    endpoint->abandon(address, why);
  }
  std::lock_guard lock(mutex);
  mark_exited(
      [&addresses](const ComponentInstance &c) {
        return std::find(addresses.begin(), addresses.end(), c.address) != addresses.end();
      },
      why);
  return Json::object();
}

void DomainManager::Impl::mark_exited(const std::function<bool(const ComponentInstance &)> &which,
                                      const std::string &why) {
  for (auto &[name, app] : applications) {
    if (!app)
      continue;
    for (auto &c : app->components) {
      if (c.pid == 0 || c.state == "exited" || !which(c))
        continue;
      components.exited(c.address, why);
      c.state = "exited";
      spdlog::warn("component {} of application {} exited unexpectedly: {}", c.id, name, why);
      events->publish("component.exited",
                      {{"application", name}, {"component", c.id}, {"node", c.node}, {"why", why}});
    }
  }
}

// A component saw its writer miss a connection's deadline or lose liveliness.
CallResult<Json> DomainManager::Impl::connection_problem(const Json &body) {
  const Json details{{"application", body.value("application", "")},
                     {"component", body.value("component", "")},
                     {"connection", body.value("connection", "")},
                     {"problem", body.value("problem", "")},
                     {"count", body.value("count", 0)}};
  spdlog::warn("connection {} of application {} ({}): {} ({} times)",
               details.at("connection").get<std::string>(),
               details.at("application").get<std::string>(),
               details.at("component").get<std::string>(), details.at("problem").get<std::string>(),
               details.at("count").get<int>());
  events->publish("connection.problem", details);
  return Json::object();
}

void DomainManager::Impl::on_announcement(const control::AnnouncementEvent &event) {
  if (event.kind == control::AnnouncementEvent::Kind::Alive && event.endpoint_kind == "node") {
    const std::string node = event.body.value("node", event.address);
    allocator.set_node_devices(node, devices_of(node, event.body));
    std::lock_guard lock(mutex);
    const bool known = nodes.count(node) != 0;
    nodes[node] = {node, event.address, event.body};
    runtime_connections->endpoints_changed(); // connections waiting for its devices
    if (!known) {
      spdlog::info("node {} registered with {} device(s)", node,
                   event.body.value("devices", Json::array()).size());
      events->publish("node.added", {{"node", node}, {"devices", device_ids(event.body)}});
    }
    return;
  }
  if (event.kind == control::AnnouncementEvent::Kind::Alive && event.endpoint_kind == "component") {
    components.announced(event.address, event.body);
    return;
  }
  if (event.kind != control::AnnouncementEvent::Kind::Gone)
    return;
  components.gone(event.address);
  std::lock_guard lock(mutex);
  for (auto it = nodes.begin(); it != nodes.end(); ++it) {
    if (it->second.address != event.address)
      continue;
    spdlog::warn("node {} is gone; its devices leave the domain", it->first);
    events->publish("node.removed",
                    {{"node", it->first}, {"devices", device_ids(it->second.body)}});
    allocator.remove_node(it->first);
    // Its component processes died with it (they cannot outlive their node); their own leases
    // are longer than a node's, so their announcements would linger.
    const auto why = fmt::format("its node {} is gone", it->first);
    for (const auto &address : components.node_gone(it->first, why))
      endpoint->abandon(address, why);
    mark_exited([&node = it->first](const ComponentInstance &c) { return c.node == node; }, why);
    runtime_connections->owner_gone_later([prefix = it->first + ":"](const PortRef &ref) {
      return ref.kind == PortRef::Kind::Device && ref.owner.starts_with(prefix);
    });
    nodes.erase(it);
    return;
  }
}

void DomainManager::Impl::serve() {
  auto bind = [this](const char *op, auto method) {
    endpoint->on(op, [this, method](const Json &body, const control::RequestContext &) {
      return (this->*method)(body);
    });
  };
  auto bind0 = [this](const char *op, auto method) {
    endpoint->on(op, [this, method](const Json &, const control::RequestContext &) {
      return (this->*method)();
    });
  };
  bind("domain.install", &Impl::install);
  bind("domain.uninstall", &Impl::uninstall);
  bind0("domain.installed", &Impl::list_installed);
  bind0("domain.nodes", &Impl::list_nodes);
  bind0("domain.devices", &Impl::list_devices);
  bind("domain.component_exited", &Impl::component_exited);
  bind("domain.connection_problem", &Impl::connection_problem);
  bind("app.create", &Impl::create_application);
  bind("app.plan", &Impl::plan_application);
  bind0("channel.list", &Impl::list_channels);
  bind("channel.create", &Impl::create_channel);
  bind("channel.destroy", &Impl::destroy_channel);
  bind("connection.list", &Impl::list_connections);
  bind("connection.create", &Impl::create_connection);
  bind("connection.destroy", &Impl::destroy_connection);
  bind("app.progress", &Impl::progress);
  bind("app.cancel", &Impl::cancel_launch);
  bind("app.release", &Impl::release);
  bind("app.configure", &Impl::configure);
  bind("app.query", &Impl::query);
  endpoint->on("app.list",
               [this](const Json &, const control::RequestContext &) -> CallResult<Json> {
                 std::lock_guard lock(mutex);
                 Json list = Json::array();
                 for (const auto &[name, app] : applications)
                   if (app)
                     list.push_back({{"name", name},
                                     {"installed", app->installed},
                                     {"state", to_string(app->state)},
                                     {"components", app->components.size()}});
                 return Json{{"applications", list}};
               });
  endpoint->on("app.show",
               [this](const Json &body, const control::RequestContext &) -> CallResult<Json> {
                 auto app = find_application(body);
                 if (!app)
                   return tl::unexpected(app.error());
                 std::lock_guard lock(mutex);
                 return to_json(**app);
               });
  for (const char *op : {"app.start", "app.stop"}) {
    const bool starting = std::string_view(op) == "app.start";
    endpoint->on(
        op,
        [this, starting](const Json &body, const control::RequestContext &) -> CallResult<Json> {
          auto app = find_application(body);
          if (!app)
            return tl::unexpected(app.error());
          auto ok = starting ? factory().start(**app) : factory().stop(**app);
          if (!ok)
            return tl::unexpected(ok.error());
          return to_json(**app);
        });
  }
}

DomainManager::DomainManager(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

DomainManager::~DomainManager() {
  // Releasing applications is the operator's decision; the domain only stops serving.
  impl_->runtime_connections->stop(); // its thread calls through the endpoint
  impl_->endpoint.reset();
}

Expected<std::unique_ptr<DomainManager>>
DomainManager::create(std::shared_ptr<dds::Participant> participant, DomainOptions options) {
  auto impl = std::make_unique<Impl>();
  impl->options = std::move(options);
  impl->participant = participant;
  impl->channels.emplace(impl->options.name);
  std::error_code ec;
  fs::create_directories(impl->options.repository, ec);
  if (ec)
    return make_error({impl->options.repository.string(), 0, 0}, "io", ec.message());
  auto store = DomainStore::open(impl->options.repository / "domain.sqlite");
  if (!store)
    return tl::unexpected(store.error());
  impl->store.emplace(std::move(*store));
  auto events = control::DomainEvents::open(participant, impl->options.name);
  if (!events)
    return tl::unexpected(events.error());
  impl->events = std::move(*events);
  if (auto ok = impl->load_installed(); !ok)
    return tl::unexpected(ok.error());
  Impl *raw = impl.get();
  impl->runtime_connections.emplace(
      impl->options.name, impl->endpoint,
      [raw](const PortRef &ref, profile::PortDirection direction) {
        return raw->resolve_end(ref, direction);
      },
      impl->options.call_timeout);
  auto endpoint = control::Endpoint::open(
      participant, address_of(impl->options.name),
      {.workers = 16,
       .senders = 4,
       .on_announcement = [raw](const control::AnnouncementEvent &e) { raw->on_announcement(e); },
       .aliases = {},
       .prepare_kinds = {"node"}});
  if (!endpoint)
    return tl::unexpected(endpoint.error());
  impl->endpoint = std::move(*endpoint);
  // Before serving: a connection requested meanwhile could take a restored one's id.
  impl->restore_connections();
  impl->serve();
  spdlog::info("domain {} serving at {}", impl->options.name, impl->endpoint->address());
  return std::unique_ptr<DomainManager>(new DomainManager(std::move(impl)));
}

} // namespace rsca::domain
