// The DomainManager's installs and applications: install and uninstall, launch (create), start,
// stop, release, configure, query, and what it does when a component exits. Nodes, devices,
// connections and channels are in domain_connections.cpp.
#include "domain/domain_manager.hpp"

#include <algorithm>
#include <sstream>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "allocator/plan_json.hpp"
#include "common/elapsed.hpp"
#include "common/names.hpp"
#include "control/operation.hpp"
#include "domain/domain_manager_impl.hpp"
#include "profile/property_binding.hpp"
#include "profile/property_json.hpp"
#include "protocol/addresses.hpp"
#include "protocol/component_ops.hpp"

namespace rsca::domain {
namespace {

namespace fs = std::filesystem;
using control::Json;
using control::Status;

Json steps_json(const std::vector<LaunchStep> &steps) {
  Json out = Json::array();
  for (const auto &s : steps)
    out.push_back({{"step", s.step}, {"detail", s.detail}, {"ms", s.milliseconds}});
  return out;
}

CallResult<InstallRequest> install_request_of(const Json &body) {
  auto sad = required<std::string>(body, "sad");
  auto files = required<std::vector<Json>>(body, "files");
  auto name = optional_field<std::string>(body, "name");
  if (!sad || !files || !name)
    return tl::unexpected(!sad ? sad.error() : !files ? files.error() : name.error());
  InstallRequest request{*sad, {}, *name};
  for (const auto &f : *files) {
    auto path = required<std::string>(f, "path");
    auto content = required<std::string>(f, "content");
    if (!path || !content)
      return tl::unexpected(path ? content.error() : path.error());
    request.files.push_back({std::move(*path), std::move(*content)});
  }
  return request;
}

// The assignments and strategy a launch or plan request gives.
CallResult<std::pair<std::map<std::string, std::string>, std::optional<allocator::Strategy>>>
placement_options(const Json &body) {
  auto assign = optional_field<std::map<std::string, std::string>>(body, "assign");
  auto strategy_name = optional_field<std::string>(body, "strategy");
  if (!assign || !strategy_name)
    return tl::unexpected(assign ? strategy_name.error() : assign.error());
  std::optional<allocator::Strategy> strategy;
  if (*strategy_name) {
    strategy = allocator::parse_strategy(**strategy_name);
    if (!strategy)
      return control::call_error(Status::BadRequest,
                                 fmt::format("unknown placement strategy \"{}\": pack or spread",
                                             excerpt(**strategy_name)));
  }
  return std::pair{assign->value_or(std::map<std::string, std::string>{}), strategy};
}

// The domain answered, so a peer that did not (a component) is a failure of the operation, not
// an unreachable domain: the CLI tells the two apart by status.
CallResult<Json> as_domain_reply(CallResult<Json> result) {
  if (!result &&
      (result.error().status == Status::Unavailable || result.error().status == Status::Timeout))
    result.error().status = Status::Failed;
  return result;
}

} // namespace

ApplicationFactory DomainManager::Impl::factory() {
  DomainServices s;
  s.domain_name = options.name;
  s.endpoint = endpoint.get();
  s.allocator = &allocator;
  s.components = &components;
  s.channels = &*channels;
  s.node_address = [this](const std::string &node) { return nodes.address_of(node); };
  s.device_ports = [this](const std::string &id) -> std::optional<DevicePorts> {
    auto device = nodes.device(id);
    if (!device || device->address.empty())
      return std::nullopt;
    return DevicePorts{std::move(device->address), std::move(device->ports)};
  };
  s.next_launch = [this] { return LaunchIdentity{incarnation, ++launch_counter}; };
  s.call_timeout = options.call_timeout;
  s.registration_timeout = options.registration_timeout;
  s.strategy = options.strategy;
  return ApplicationFactory(std::move(s));
}

ApplicationFactory::ApplyChange DomainManager::Impl::apply_to(const std::string &name) {
  return [this, name](const std::function<void(Application &)> &change) {
    applications.update(name, change);
  };
}

CallResult<Json> DomainManager::Impl::install(const Json &body) {
  auto request = install_request_of(body);
  if (!request)
    return tl::unexpected(request.error());
  auto installed = repository->install(*request);
  if (!installed)
    return tl::unexpected(installed.error());
  spdlog::info("installed application {} ({} files)", installed->name, request->files.size());
  Json warnings = Json::array();
  for (const auto &w : installed->profile->warnings)
    warnings.push_back(to_string(w));
  return Json{{"name", installed->name}, {"warnings", warnings}};
}

CallResult<Json> DomainManager::Impl::uninstall(const Json &body) {
  auto name = required<std::string>(body, "name");
  if (!name)
    return tl::unexpected(name.error());
  std::lock_guard lock(installs);
  // Its launch would run from files that are gone, and come back after a restart of the domain.
  if (applications.launching(*name))
    return control::call_error(
        Status::Rejected,
        fmt::format("a launch of {} is under way: uninstall it once the launch has ended", *name));
  if (auto removed = repository->uninstall(*name); !removed)
    return tl::unexpected(removed.error());
  for (const auto &running : applications.running_from(*name))
    spdlog::info("{} stays running after uninstalling {}", running, *name);
  spdlog::info("uninstalled application {}", *name);
  return Json{{"name", *name}};
}

CallResult<Json> DomainManager::Impl::list_installed() {
  Json list = Json::array();
  for (const auto &app : repository->list()) {
    std::size_t count = 0;
    for (const auto &p : app.profile->sad->placements)
      count += p.instantiations.size();
    list.push_back({{"name", app.name}, {"sad", app.sad.string()}, {"components", count}});
  }
  return Json{{"applications", list}};
}

CallResult<Json> DomainManager::Impl::create_application(const Json &body) {
  auto installed_name = required<std::string>(body, "application");
  auto wanted = optional_field<std::string>(body, "name");
  auto launch_id = optional_field<std::string>(body, "launch_id");
  auto start = optional_field<bool>(body, "start");
  auto placement = placement_options(body);
  if (!installed_name || !wanted || !launch_id || !start || !placement)
    return control::call_error(Status::BadRequest, (!installed_name ? installed_name.error()
                                                    : !wanted       ? wanted.error()
                                                    : !launch_id    ? launch_id.error()
                                                    : !start        ? start.error()
                                                                    : placement.error())
                                                       .message);
  if (*wanted)
    if (auto named = check_name("the application", **wanted); !named)
      return control::call_error(Status::BadRequest, named.error());
  LaunchRequest request;
  {
    std::lock_guard lock(installs);
    auto installed = repository->find(*installed_name);
    if (!installed)
      return control::call_error(Status::NotFound, fmt::format("no application {} is installed",
                                                               excerpt(*installed_name)));
    auto name = applications.reserve(wanted->value_or(*installed_name), wanted->has_value(),
                                     *installed_name);
    if (!name)
      return tl::unexpected(name.error());
    request.name = *name;
    request.installed = *installed_name;
    request.profile = installed->profile;
  }
  request.start = start->value_or(true);
  std::tie(request.assignments, request.strategy) = *placement;
  const std::string id = launch_id->value_or(request.name);
  const auto began = std::chrono::steady_clock::now();
  std::vector<LaunchStep> steps;
  auto app = launch(request, id, steps);
  if (!app) {
    applications.drop(request.name);
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
  Json reply = to_json(**app);
  applications.commit(*app);
  runtime_connections->endpoints_changed(); // connections waiting for it
  reply["launch"] = {{"steps", steps_json(steps)}, {"ms", ms_since(began)}};
  return reply;
}

// The launch itself, its name reserved: cancelled before it begins, run, or released at once when
// its cancel came after its last step (its caller was told it would not run). `steps` receives
// the steps it made.
CallResult<std::shared_ptr<Application>>
DomainManager::Impl::launch(LaunchRequest &request, const std::string &launch_id,
                            std::vector<LaunchStep> &steps) {
  request.cancelled = launches.begin(launch_id);
  if (!request.cancelled) {
    spdlog::info("launch {} of {} not begun: its caller cancelled it first", launch_id,
                 request.installed);
    return control::call_error(
        Status::Failed,
        fmt::format("the launch of {} was cancelled before it began", request.installed));
  }
  auto record = [this, &launch_id](const LaunchStep &step) { launches.record(launch_id, step); };
  auto app = factory().create(request, record);
  if (auto recorded = launches.progress(launch_id)) // before finish: it may forget the launch
    steps = recorded->steps;
  if (launches.finish(launch_id, app.has_value()))
    return app;
  if (auto released = factory().release(**app); !released)
    spdlog::warn("application {} launched as its cancel came; releasing it failed: {}",
                 request.name, released.error().message);
  else
    spdlog::warn("application {} launched as its cancel came; released", request.name);
  launches.finish(launch_id, false);
  return control::call_error(
      Status::Failed,
      fmt::format("launch of {} cancelled after its last step; released", request.name));
}

CallResult<Json> DomainManager::Impl::progress(const Json &body) {
  auto id = required<std::string>(body, "launch_id");
  if (!id)
    return tl::unexpected(id.error());
  auto progress = launches.progress(*id);
  if (!progress)
    return control::call_error(Status::NotFound, fmt::format("no launch {}", excerpt(*id)));
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

CallResult<Json> DomainManager::Impl::release(const Json &body) {
  auto name = required<std::string>(body, "app");
  if (!name)
    return tl::unexpected(name.error());
  auto found = applications.find(*name);
  if (!found)
    return tl::unexpected(found.error());
  std::lock_guard lifecycle(*found->lifecycle); // a start or stop under way ends first
  auto removed = applications.remove(*name);
  if (!removed)
    return control::call_error(Status::NotFound, fmt::format("application {} was released "
                                                             "meanwhile",
                                                             *name));
  // Its runtime connections wait for it again; their other ends are disconnected. Only now that
  // it can no longer be found: a retry of pending connections in between would wire them to it.
  runtime_connections->owner_gone([&name](const PortRef &ref) {
    return ref.kind != PortRef::Kind::Device && ref.owner == *name;
  });
  auto unconfirmed = factory().release(*removed->app);
  spdlog::info("application {} released", *name);
  events->publish("application.released", {{"application", *name}});
  if (!unconfirmed)
    return control::call_error(
        unconfirmed.error().status,
        fmt::format("released {} with problems: {}", *name, unconfirmed.error().message));
  return Json{{"name", *name}, {"unconfirmed", *unconfirmed}};
}

// Start and stop of one application are serialized (its lifecycle lock) and work from a copy;
// its state changes only through the registry.
CallResult<Json> DomainManager::Impl::start_or_stop(const Json &body, bool start) {
  auto name = required<std::string>(body, "app");
  if (!name)
    return tl::unexpected(name.error());
  auto found = applications.find(*name);
  if (!found)
    return tl::unexpected(found.error());
  std::lock_guard lifecycle(*found->lifecycle);
  auto app = applications.snapshot(*name);
  if (!app)
    return control::call_error(Status::NotFound,
                               fmt::format("application {} was released meanwhile", *name));
  auto done =
      start ? factory().start(*app, apply_to(*name)) : factory().stop(*app, apply_to(*name));
  if (!done)
    return tl::unexpected(done.error());
  auto now = applications.snapshot(*name);
  return now ? to_json(*now) : Json{{"name", *name}};
}

CallResult<Json> DomainManager::Impl::list_applications() {
  Json list = Json::array();
  for (const auto &app : applications.snapshots())
    list.push_back({{"name", app.name},
                    {"installed", app.installed},
                    {"state", state_of(app)},
                    {"exited", exited_components(app)},
                    {"components", app.components.size()}});
  return Json{{"applications", list}, {"unknown", unknown_components()}};
}

CallResult<Json> DomainManager::Impl::show_application(const Json &body) {
  auto name = required<std::string>(body, "app");
  if (!name)
    return tl::unexpected(name.error());
  auto app = applications.snapshot(*name);
  if (!app)
    return control::call_error(Status::NotFound,
                               fmt::format("no application {} is running", excerpt(*name)));
  return to_json(*app);
}

// Admission and placement of an installed application on the domain as it is, reserving nothing.
CallResult<Json> DomainManager::Impl::plan_application(const Json &body) {
  auto name = required<std::string>(body, "application");
  if (!name)
    return tl::unexpected(name.error());
  auto placement = placement_options(body);
  if (!placement)
    return tl::unexpected(placement.error());
  auto installed = repository->find(*name);
  if (!installed)
    return control::call_error(Status::NotFound,
                               fmt::format("no application {} is installed", excerpt(*name)));
  const allocator::PlanOptions plan_options{placement->second.value_or(options.strategy)};
  auto plan = allocator.plan(allocator::plan_request_of(*installed->profile, placement->first),
                             plan_options);
  const std::string strategy(to_string(plan_options.strategy));
  if (!plan)
    return Json{{"admitted", false},
                {"rejections", allocator::to_json(plan.error())},
                {"strategy", strategy}};
  return Json{{"admitted", true}, {"plan", allocator::to_json(*plan)}, {"strategy", strategy}};
}

void DomainManager::Impl::serve() {
  // Every handler's reply passes as_domain_reply; a field of the wrong type is a BadRequest
  // (required, optional_field) or, where read with a default, caught by the endpoint.
  auto bind = [this](const char *op, auto method) {
    endpoint->on(op, [this, method](const Json &body, const control::RequestContext &) {
      return as_domain_reply((this->*method)(body));
    });
  };
  auto bind0 = [this](const char *op, auto method) {
    endpoint->on(op, [this, method](const Json &, const control::RequestContext &) {
      return as_domain_reply((this->*method)());
    });
  };
  bind("domain.install", &Impl::install);
  bind("domain.uninstall", &Impl::uninstall);
  bind0("domain.installed", &Impl::list_installed);
  bind0("domain.nodes", &Impl::list_nodes);
  bind0("domain.devices", &Impl::list_devices);
  control::serve<protocol::domain::ComponentExited>(
      *endpoint, [this](const auto &report, const auto &) { return component_exited(report); });
  control::serve<protocol::domain::ConnectionProblem>(
      *endpoint, [this](const auto &report, const auto &) { return connection_problem(report); });
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
  bind0("app.list", &Impl::list_applications);
  bind("app.show", &Impl::show_application);
  endpoint->on("app.start", [this](const Json &body, const control::RequestContext &) {
    return as_domain_reply(start_or_stop(body, true));
  });
  endpoint->on("app.stop", [this](const Json &body, const control::RequestContext &) {
    return as_domain_reply(start_or_stop(body, false));
  });
}

DomainManager::DomainManager(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

DomainManager::~DomainManager() {
  // Releasing applications is the operator's decision; the domain only stops serving.
  impl_->runtime_connections->stop(); // its thread calls through the endpoint
  // The handlers reach the endpoint through impl_->endpoint, which reset() clears before the
  // endpoint's destructor waits for them (ThreadSanitizer saw connection.list read it meanwhile).
  impl_->endpoint->stop_serving();
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
  auto incarnation = impl->store->next_incarnation();
  if (!incarnation)
    return tl::unexpected(incarnation.error());
  impl->incarnation = *incarnation;
  auto events = control::DomainEvents::open(participant, impl->options.name);
  if (!events)
    return tl::unexpected(events.error());
  impl->events = std::move(*events);
  impl->repository.emplace(impl->options.repository, *impl->store);
  impl->repository->load();
  Impl *raw = impl.get();
  impl->runtime_connections.emplace(
      impl->options.name, impl->endpoint,
      [raw](const PortRef &ref, profile::PortDirection direction) {
        return raw->resolve_end(ref, direction);
      },
      impl->options.call_timeout);
  auto endpoint = control::Endpoint::open(
      participant, protocol::domain_address(impl->options.name),
      {.workers = 16,
       .senders = 4,
       .on_announcement = [raw](const control::AnnouncementEvent &e) { raw->on_announcement(e); },
       .aliases = {},
       .prepare_kinds = {"node"},
       .hold_requests = true});
  if (!endpoint)
    return tl::unexpected(endpoint.error());
  impl->endpoint = std::move(*endpoint);
  // Before serving: a connection requested meanwhile could take a restored one's id.
  impl->restore_connections();
  impl->serve();
  impl->endpoint->start_serving();
  spdlog::info("domain {} serving at {} (incarnation {})", impl->options.name,
               impl->endpoint->address(), impl->incarnation);
  return std::unique_ptr<DomainManager>(new DomainManager(std::move(impl)));
}

} // namespace rsca::domain
