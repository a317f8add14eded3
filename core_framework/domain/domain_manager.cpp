// The DomainManager's installs and applications: install and uninstall, launch (create), start,
// stop, release, configure, query, and what it does when a component exits. Nodes, devices,
// connections and channels are in domain_connections.cpp.
#include "domain/domain_manager.hpp"

#include <unistd.h>

#include <algorithm>
#include <functional>
#include <sstream>
#include <type_traits>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "allocator/plan_json.hpp"
#include "common/elapsed.hpp"
#include "common/host_name.hpp"
#include "common/names.hpp"
#include "control/name_holder.hpp"
#include "control/operation.hpp"
#include "domain/domain_manager_impl.hpp"
#include "profile/property_binding.hpp"
#include "profile/property_json.hpp"
#include "protocol/addresses.hpp"
#include "protocol/component_ops.hpp"
#include "protocol/domain_announcement.hpp"

namespace rsca::domain {
namespace {

namespace fs = std::filesystem;
using control::Json;
using control::Status;

std::vector<app_ops::StepView> steps_of(const std::vector<LaunchStep> &steps) {
  std::vector<app_ops::StepView> out;
  for (const auto &s : steps)
    out.push_back({s.step, s.detail, s.milliseconds});
  return out;
}

// The strategy a launch or plan request names, if any.
CallResult<std::optional<allocator::Strategy>> strategy_of(const std::optional<std::string> &name) {
  if (!name)
    return std::nullopt;
  auto strategy = allocator::parse_strategy(*name);
  if (!strategy)
    return control::call_error(
        Status::BadRequest,
        fmt::format("unknown placement strategy \"{}\": pack or spread", excerpt(*name)));
  return strategy;
}

// The domain answered, so a peer that did not (a component) is a failure of the operation, not
// an unreachable domain: the CLI tells the two apart by status.
template <typename Reply>
CallResult<Reply> as_domain_reply(CallResult<Reply> result) {
  if (!result &&
      (result.error().status == Status::Unavailable || result.error().status == Status::Timeout))
    result.error().status = Status::Failed;
  return result;
}

// Why this daemon must not serve domain `name`: another daemon of that name lives on the same DDS
// domain and tag (control/name_holder.hpp). Two would both take the domain's requests, and the
// one that stops first would take the other's nodes and applications with it.
std::optional<std::string> held_by_another(const dds::Participant &participant,
                                           const std::string &name) {
  spdlog::info("looking for another daemon of domain {} (up to {} ms)", name,
               control::kNameCheck.count());
  auto held = control::live_holder<protocol::domain::DomainAnnouncement>(
      participant, protocol::domain_address(name), fmt::format("domain {}", name),
      control::own_program());
  if (!held)
    return std::nullopt;
  return fmt::format("{}: this daemon (pid {} on host {}) does not start beside it; stop that one "
                     "first, or give this one another DDS domain or tag (RSCA_DDS_DOMAIN, "
                     "RSCA_DDS_TAG)",
                     *held, ::getpid(), host_name());
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
  s.node_relays = [this](const std::string &node) { return nodes.relays_processes(node); };
  s.device_ports = [this](const std::string &id) -> std::optional<DevicePorts> {
    auto device = nodes.device(id);
    if (!device || device->address.empty())
      return std::nullopt;
    return DevicePorts{std::move(device->address), std::move(device->ports)};
  };
  s.next_launch = [this] { return LaunchIdentity{incarnation, ++launch_counter}; };
  s.files = &*files;
  s.end_when_back = [this](const std::string &node, long pid, const std::string &label) {
    end_when_back(node, pid, label);
  };
  s.launch_failed = [this](app_ops::FailedLaunch failed) { launches.failed(std::move(failed)); };
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

CallResult<domain_ops::InstallReply>
DomainManager::Impl::install(const domain_ops::InstallRequest &request) {
  auto installed = repository->install(request);
  if (!installed)
    return tl::unexpected(installed.error());
  spdlog::info("installed application {} ({} files)", installed->name, request.files.size());
  domain_ops::InstallReply reply{installed->name, {}};
  for (const auto &w : installed->profile->warnings)
    reply.warnings.push_back(to_string(w));
  for (const auto &w : installed->profile->tolerated)
    reply.warnings.push_back(to_string(w));
  return reply;
}

CallResult<domain_ops::Named> DomainManager::Impl::uninstall(const domain_ops::Named &request) {
  const std::string &name = request.name;
  std::lock_guard lock(installs);
  // Its launch would run from files that are gone, and come back after a restart of the domain.
  if (applications.launching(name))
    return control::call_error(
        Status::Rejected,
        fmt::format("a launch of {} is under way: uninstall it once the launch has ended", name));
  if (auto removed = repository->uninstall(name); !removed)
    return tl::unexpected(removed.error());
  for (const auto &running : applications.running_from(name))
    spdlog::info("{} stays running after uninstalling {}", running, name);
  spdlog::info("uninstalled application {}", name);
  return request;
}

CallResult<domain_ops::InstalledReply> DomainManager::Impl::list_installed() {
  domain_ops::InstalledReply reply;
  for (const auto &app : repository->list()) {
    std::size_t count = 0;
    for (const auto &p : app.profile->sad->placements)
      count += p.instantiations.size();
    reply.applications.push_back({app.name, app.sad.string(), count});
  }
  return reply;
}

namespace {

tl::unexpected<control::CallError> unknown_assignment_error(const std::string &application,
                                                            const std::string &component) {
  return control::call_error(Status::BadRequest,
                             fmt::format("assign names {}, which is no component of {}",
                                         excerpt(component), excerpt(application)));
}

} // namespace

// A launch that settles the install made for it (`rsca launch SAD`) keeps it or puts back what it
// replaced (InstalledRepository::settle); its error then says which.
CallResult<app_ops::CreateReply>
DomainManager::Impl::create_application(const app_ops::CreateRequest &wire) {
  auto created = create_installed(wire);
  if (!wire.settles_install.value_or(false))
    return created;
  std::lock_guard lock(installs);
  const auto settled = repository->settle(wire.application, created.has_value());
  if (!created && !settled.empty())
    created.error().message += "; " + settled;
  return created;
}

CallResult<app_ops::CreateReply>
DomainManager::Impl::create_installed(const app_ops::CreateRequest &wire) {
  if (wire.name)
    if (auto named = check_name("the application", *wire.name); !named)
      return control::call_error(Status::BadRequest, named.error());
  auto strategy = strategy_of(wire.strategy);
  if (!strategy)
    return tl::unexpected(strategy.error());
  LaunchRequest request;
  {
    std::lock_guard lock(installs);
    auto installed = repository->find(wire.application);
    if (!installed)
      return control::call_error(Status::NotFound, fmt::format("no application {} is installed",
                                                               excerpt(wire.application)));
    if (auto stray = allocator::unknown_assignment(*installed->profile, wire.assign))
      return unknown_assignment_error(wire.application, *stray);
    auto name = applications.reserve(wire.name.value_or(wire.application), wire.name.has_value(),
                                     wire.application);
    if (!name)
      return tl::unexpected(name.error());
    request.name = *name;
    request.installed = wire.application;
    request.profile = installed->profile;
  }
  request.start = wire.start;
  request.assignments = wire.assign;
  request.strategy = *strategy;
  const std::string id = wire.launch_id.value_or(request.name);
  request.id = id;
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
                                          {"components", (*app)->components.size()},
                                          {"started", request.start}});
  app_ops::CreateReply reply{view_of(**app), {steps_of(steps), ms_since(began)}};
  applications.commit(*app);
  runtime_connections->endpoints_changed(); // connections waiting for it
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

CallResult<app_ops::ProgressReply> DomainManager::Impl::progress(const app_ops::LaunchId &request) {
  auto progress = launches.progress(request.launch_id);
  if (!progress)
    return control::call_error(Status::NotFound,
                               fmt::format("no launch {}", excerpt(request.launch_id)));
  app_ops::ProgressReply reply{steps_of(progress->steps), progress->done, std::nullopt,
                               std::nullopt};
  if (const auto delivered = files->delivered(request.launch_id); delivered.bytes > 0) {
    reply.delivered_bytes = delivered.bytes;
    reply.delivered_wire_bytes = delivered.wire_bytes;
  }
  return reply;
}

// A node fetching a piece of a file of a package it was sent. Its launch names a launch only to
// count the bytes for that launch's progress: bounded, as everything from the network.
CallResult<protocol::file::ReadReply>
DomainManager::Impl::read_file(const protocol::file::ReadRequest &request) {
  if (request.launch && request.launch->size() > protocol::file::kMaxLaunchLength)
    return control::call_error(Status::BadRequest, "launch: an id too long");
  return files->read(request);
}

// A caller that stops waiting for its launch (the CLI's own deadline) cancels it, so that no
// application it gave up on appears later: the launch rolls back at its next step, or at once
// when it is waiting for registrations. A cancel that overtook its create is kept: that launch
// never begins.
CallResult<app_ops::CancelReply>
DomainManager::Impl::cancel_launch(const app_ops::LaunchId &request) {
  const std::string &id = request.launch_id;
  const auto outcome = launches.cancel(id);
  if (!outcome.cancelled)
    return app_ops::CancelReply{false, true, std::nullopt};
  if (!outcome.begun) {
    spdlog::info("launch {} cancelled by its caller before it began", id);
    return app_ops::CancelReply{true, false, false};
  }
  spdlog::info("launch {} cancelled by its caller", id);
  components.interrupt();
  return app_ops::CancelReply{true, false, true};
}

CallResult<app_ops::ReleaseReply> DomainManager::Impl::release(const app_ops::AppRequest &request) {
  const std::string &name = request.app;
  auto found = applications.find(name);
  if (!found)
    return tl::unexpected(found.error());
  std::lock_guard lifecycle(*found->lifecycle); // a start or stop under way ends first
  auto removed = applications.remove(name);
  if (!removed)
    return control::call_error(Status::NotFound, fmt::format("application {} was released "
                                                             "meanwhile",
                                                             name));
  // Its runtime connections wait for it again; their other ends are disconnected. Only now that
  // it can no longer be found: a retry of pending connections in between would wire them to it.
  runtime_connections->owner_gone([&name](const PortRef &ref) {
    return ref.kind != PortRef::Kind::Device && ref.owner == name;
  });
  auto released = factory().release(*removed->app);
  spdlog::info("application {} released", name);
  events->publish("application.released", {{"application", name}});
  if (!released)
    return control::call_error(
        released.error().status,
        fmt::format("released {} with problems: {}", name, released.error().message));
  app_ops::ReleaseReply reply{name, std::move(released->unconfirmed), std::nullopt};
  if (!released->lost.empty())
    reply.to_end_later = std::move(released->lost);
  return reply;
}

// Start and stop of one application are serialized (its lifecycle lock) and work from a copy;
// its state changes only through the registry.
CallResult<app_ops::ApplicationView>
DomainManager::Impl::start_or_stop(const app_ops::AppRequest &request, bool start) {
  const std::string &name = request.app;
  auto found = applications.find(name);
  if (!found)
    return tl::unexpected(found.error());
  std::lock_guard lifecycle(*found->lifecycle);
  auto app = applications.snapshot(name);
  if (!app)
    return control::call_error(Status::NotFound,
                               fmt::format("application {} was released meanwhile", name));
  // Its unreachable components could not follow: when their node is back they would be left in
  // the state they had, at odds with the application's.
  if (const auto unreachable = unreachable_components(*app); !unreachable.empty())
    return control::call_error(
        Status::Unavailable,
        fmt::format("application {} cannot {}: {} {} unreachable (its node is lost); try again "
                    "when it is back",
                    name, start ? "start" : "stop", fmt::join(unreachable, ", "),
                    unreachable.size() == 1 ? "is" : "are"));
  auto done = start ? factory().start(*app, apply_to(name)) : factory().stop(*app, apply_to(name));
  if (!done)
    return tl::unexpected(done.error());
  events->publish(start ? "application.started" : "application.stopped", {{"application", name}});
  // A release waits for the lifecycle lock held here: the application is still there.
  auto now = applications.snapshot(name);
  return view_of(now ? *now : *app);
}

CallResult<app_ops::ListReply> DomainManager::Impl::list_applications() {
  app_ops::ListReply reply;
  for (const auto &app : applications.snapshots())
    reply.applications.push_back({app.name, app.installed, state_of(app), exited_components(app),
                                  app.components.size(), unreachable_components(app)});
  reply.unknown = unknown_components();
  return reply;
}

CallResult<app_ops::ApplicationView>
DomainManager::Impl::show_application(const app_ops::AppRequest &request) {
  auto app = applications.snapshot(request.app);
  if (!app)
    return control::call_error(Status::NotFound,
                               fmt::format("no application {} is running", excerpt(request.app)));
  return live_view_of(*app);
}

// Admission and placement of an application on the domain as it is, reserving nothing.
CallResult<app_ops::PlanReply>
DomainManager::Impl::plan_profile(const profile::ResolvedApplication &profile,
                                  const std::string &name,
                                  const std::map<std::string, std::string> &assign,
                                  const std::optional<std::string> &strategy_name) {
  auto strategy = strategy_of(strategy_name);
  if (!strategy)
    return tl::unexpected(strategy.error());
  if (auto stray = allocator::unknown_assignment(profile, assign))
    return unknown_assignment_error(name, *stray);
  const allocator::PlanOptions plan_options{strategy->value_or(options.strategy)};
  auto plan = allocator.plan(allocator::plan_request_of(profile, assign), plan_options);
  return allocator::plan_reply(plan, plan_options.strategy);
}

CallResult<app_ops::PlanReply>
DomainManager::Impl::plan_application(const app_ops::PlanRequest &request) {
  auto installed = repository->find(request.application);
  if (!installed)
    return control::call_error(Status::NotFound, fmt::format("no application {} is installed",
                                                             excerpt(request.application)));
  return plan_profile(*installed->profile, request.application, request.assign, request.strategy);
}

// The same of an application's files, read aside and removed again: nothing is installed.
CallResult<app_ops::PlanReply>
DomainManager::Impl::plan_files(const app_ops::PlanFilesRequest &request) {
  auto profile = repository->read_aside(request.files);
  if (!profile)
    return tl::unexpected(profile.error());
  const auto &sad = *(*profile)->sad;
  const std::string name = sad.name.empty() ? sad.id : sad.name;
  auto planned = plan_profile(**profile, name, request.assign, request.strategy);
  spdlog::info("planned {} from its files, installing nothing: {}", excerpt(name),
               !planned            ? "refused"
               : planned->admitted ? "admitted"
                                   : "rejected");
  return planned;
}

template <control::Operation Op, typename Handler>
void DomainManager::Impl::serve_op(Handler handler) {
  using Request = typename Op::Request;
  control::serve<Op>(*endpoint, [this, handler]([[maybe_unused]] const Request &request,
                                                const control::RequestContext &) {
    if constexpr (std::is_invocable_v<Handler, Impl *, const Request &>)
      return as_domain_reply(std::invoke(handler, this, request));
    else
      return as_domain_reply(std::invoke(handler, this));
  });
}

void DomainManager::Impl::serve() {
  serve_op<domain_ops::Install>(&Impl::install);
  serve_op<domain_ops::Uninstall>(&Impl::uninstall);
  serve_op<domain_ops::Installed>(&Impl::list_installed);
  serve_op<domain_ops::Nodes>(&Impl::list_nodes);
  serve_op<domain_ops::Devices>(&Impl::list_devices);
  serve_op<domain_ops::Top>(&Impl::top);
  control::serve<domain_ops::ComponentExited>(
      *endpoint, [this](const auto &report, const auto &) { return component_exited(report); });
  control::serve<domain_ops::ConnectionProblem>(
      *endpoint, [this](const auto &report, const auto &) { return connection_problem(report); });
  serve_op<protocol::file::Read>(&Impl::read_file);
  serve_op<app_ops::Create>(&Impl::create_application);
  serve_op<app_ops::Plan>(&Impl::plan_application);
  serve_op<app_ops::PlanFiles>(&Impl::plan_files);
  serve_op<app_ops::Progress>(&Impl::progress);
  serve_op<app_ops::Cancel>(&Impl::cancel_launch);
  serve_op<app_ops::Failed>([](Impl *impl, const app_ops::FailedRequest &r) {
    return CallResult<app_ops::FailedReply>(
        app_ops::FailedReply{impl->launches.failures(r.application)});
  });
  serve_op<app_ops::Release>(&Impl::release);
  serve_op<app_ops::Start>(
      [](Impl *impl, const app_ops::AppRequest &r) { return impl->start_or_stop(r, true); });
  serve_op<app_ops::Stop>(
      [](Impl *impl, const app_ops::AppRequest &r) { return impl->start_or_stop(r, false); });
  serve_op<app_ops::Configure>(&Impl::configure);
  serve_op<app_ops::Query>(&Impl::query);
  serve_op<app_ops::List>(&Impl::list_applications);
  serve_op<app_ops::Show>(&Impl::show_application);
  serve_op<connection_ops::ListChannels>(&Impl::list_channels);
  serve_op<connection_ops::CreateChannel>(&Impl::create_channel);
  serve_op<connection_ops::DestroyChannel>(&Impl::destroy_channel);
  serve_op<connection_ops::List>(&Impl::list_connections);
  serve_op<connection_ops::Create>(&Impl::create_connection);
  serve_op<connection_ops::Destroy>(&Impl::destroy_connection);
}

DomainManager::DomainManager(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

DomainManager::~DomainManager() {
  // Releasing applications is the operator's decision; the domain only stops serving.
  impl_->stopping_node_returns = true; // a return still queued changes nothing, asks nothing
  impl_->node_returns->stop();         // its thread calls through the endpoint
  impl_->runtime_connections->stop();  // so does this one's
  // The handlers reach the endpoint through impl_->endpoint, which reset() clears before the
  // endpoint's destructor waits for them (ThreadSanitizer saw connection.list read it meanwhile).
  impl_->endpoint->stop_serving();
  impl_->endpoint.reset();
}

Expected<std::unique_ptr<DomainManager>>
DomainManager::create(std::shared_ptr<dds::Participant> participant, DomainOptions options) {
  // Before its store is touched: a namesake refused leaves the holder's as it was.
  if (auto held = held_by_another(*participant, options.name))
    return make_error({"domain " + options.name, 0, 0}, "name-taken", *held);
  auto impl = std::make_unique<Impl>();
  impl->options = std::move(options);
  impl->participant = participant;
  impl->channels.emplace(impl->options.name);
  impl->node_returns = std::make_unique<control::WorkerPool>(1);
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
  impl->files.emplace(impl->options.repository, impl->options.exec_path, impl->options.delivery);
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
  // Who serves the domain, for a namesake started later to find (held_by_another).
  const protocol::domain::DomainAnnouncement self{
      impl->options.name, static_cast<std::int64_t>(::getpid()), host_name(), impl->incarnation};
  if (auto ok = impl->endpoint->announce(protocol::domain::kDomainKind, protocol::encode(self));
      !ok)
    return tl::unexpected(ok.error());
  spdlog::info("domain {} serving at {} (incarnation {})", impl->options.name,
               impl->endpoint->address(), impl->incarnation);
  return std::unique_ptr<DomainManager>(new DomainManager(std::move(impl)));
}

} // namespace rsca::domain
