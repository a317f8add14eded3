// One launch of an application, step by step: check, allocate, execute, register, initialize,
// configure, connect (launch_wiring.cpp), start; and its rollback.
#include <algorithm>
#include <filesystem>
#include <map>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "common/elapsed.hpp"
#include "dds/port_qos.hpp"
#include "domain/launch.hpp"
#include "profile/application_checks.hpp"
#include "profile/property_binding.hpp"
#include "profile/property_json.hpp"
#include "protocol/component_ops.hpp"
#include "protocol/topics.hpp"

namespace rsca::domain {

using namespace detail;

CallResult<std::shared_ptr<Application>> ApplicationFactory::Launch::run() {
  using Step = CallResult<void> (Launch::*)();
  const std::pair<const char *, Step> steps[] = {
      {"check", &Launch::check},           {"allocate", &Launch::allocate},
      {"execute", &Launch::execute},       {"register", &Launch::await_registration},
      {"initialize", &Launch::initialize}, {"configure", &Launch::configure},
      {"connect", &Launch::connect},       {"start", &Launch::start},
  };
  for (const auto &[name, step] : steps) {
    if (std::string_view(name) == "start" && !request_.start)
      break;
    const auto began = Clock::now();
    detail_.clear();
    if (request_.cancelled && request_.cancelled->load())
      return fail(name, {Status::Failed, "cancelled before this step"});
    if (auto ok = (this->*step)(); !ok)
      return fail(name, ok.error());
    progress_({name, detail_, ms_since(began)});
  }
  saga_.commit();
  app_->state = request_.start ? ApplicationState::Running : ApplicationState::Created;
  spdlog::info("application {} launched: {} components on {}", app_->name, app_->components.size(),
               fmt::join(nodes_used(), ", "));
  return app_;
}

CallResult<void> ApplicationFactory::Launch::check() {
  if (auto refused = profile::launch_refusals(*request_.profile); !refused.empty()) {
    std::vector<std::string> problems;
    for (const auto &r : refused)
      problems.push_back(to_string(r));
    return control::call_error(Status::BadRequest, fmt::format("{}", fmt::join(problems, "\n")));
  }
  if (auto joined = s_.channels->join(channel_members()); !joined)
    return joined;
  saga_.on_undo([this] {
    const auto destroyed = s_.channels->leave(app_->name);
    return destroyed.empty()
               ? std::string("event channel memberships withdrawn")
               : fmt::format("event channels {} destroyed", fmt::join(destroyed, ", "));
  });
  detail_ = fmt::format("{} components, {} connections", count_instances(),
                        request_.profile->sad->connections.size());
  return {};
}

std::vector<std::pair<std::string, ChannelMember>>
ApplicationFactory::Launch::channel_members() const {
  std::vector<std::pair<std::string, ChannelMember>> members;
  const auto &sad = *request_.profile->sad;
  for (std::size_t i = 0; i < sad.connections.size(); ++i) {
    const auto &c = sad.connections[i];
    if (!c.publishes_to_channel() && !c.subscribes_to_channel())
      continue;
    const bool publishes = c.publishes_to_channel();
    ChannelMember m{publishes ? ChannelMember::Role::Publisher : ChannelMember::Role::Subscriber,
                    app_->name,
                    connection_id(c, i),
                    publishes ? c.uses.target.refid : c.provides.target.refid,
                    publishes ? c.uses.port : c.provides.port,
                    repid_of(c),
                    c.qos.value_or(profile::ConnectionQos{}),
                    c.filter.value_or("")};
    members.emplace_back(channel_name(c), std::move(m));
  }
  return members;
}

std::string ApplicationFactory::Launch::connection_id(const profile::Connection &c,
                                                      std::size_t index) {
  return profile::connection_id(c, index);
}

const std::string &ApplicationFactory::Launch::channel_name(const profile::Connection &c) {
  return c.publishes_to_channel() ? c.provides.target.findby.name : c.uses.target.findby.name;
}

CallResult<void> ApplicationFactory::Launch::allocate() {
  const allocator::PlanOptions options{request_.strategy.value_or(s_.strategy)};
  auto plan = s_.allocator->allocate(
      allocator::plan_request_of(*request_.profile, request_.assignments), options);
  if (!plan) {
    spdlog::warn("application {} rejected:\n{}", app_->name, allocator::to_string(plan.error()));
    return control::call_error(Status::Rejected, allocator::to_string(plan.error()));
  }
  app_->plan = std::move(*plan);
  saga_.on_undo([this] {
    std::vector<std::string> devices;
    for (const auto &p : app_->plan.placements)
      if (std::find(devices.begin(), devices.end(), p.device) == devices.end())
        devices.push_back(p.device);
    s_.allocator->release(app_->plan);
    app_->plan = {};
    return fmt::format("allocations on {} released", fmt::join(devices, ", "));
  });
  build_components();
  std::vector<std::string> where;
  for (const auto &p : app_->plan.placements)
    where.push_back(fmt::format("{}→{}", p.instance, p.device));
  detail_ = fmt::format("{}", fmt::join(where, ", "));
  for (const auto &p : app_->plan.placements)
    spdlog::info("placing {}/{} on {} (implementation {})", app_->name, p.instance, p.device,
                 p.implementation->id);
  return {};
}

// Where calls to a component go: to its node when the node relays for the processes it starts
// (protocol/node_link.hpp), else to its component host when it is hosted, else to itself.
void ApplicationFactory::Launch::route(ComponentInstance &c) {
  const auto node =
      s_.node_relays && s_.node_relays(c.node) ? s_.node_address(c.node) : std::nullopt;
  c.via = node ? *node : c.host;
  if (!c.via.empty())
    s_.endpoint->route(c.address, c.via);
  if (node && !c.host.empty())
    s_.endpoint->route(c.host, *node);
}

CallResult<void> ApplicationFactory::Launch::execute() {
  // From here on, components are expected and routed, and processes may start: undone by
  // releasing them (and terminating what runs) whatever this step gets to.
  saga_.on_undo([this] {
    auto released = ApplicationFactory(s_).release_processes(*app_);
    if (!released)
      return fmt::format("processes not all terminated: {}", released.error().message);
    const auto plural = [](std::size_t n) { return n == 1 ? "" : "es"; };
    std::string done;
    if (released->terminated != 0)
      done = fmt::format("{} process{} terminated", released->terminated,
                         plural(released->terminated));
    if (released->deferred != 0)
      done += fmt::format("{}{} process{} to end when {} node is back", done.empty() ? "" : ", ",
                          released->deferred, plural(released->deferred),
                          released->deferred == 1 ? "its" : "their");
    return done;
  });
  // Discovery of each component's endpoint starts now and overlaps with its process start.
  for (auto &c : app_->components) {
    s_.components->expect(c.address, c.node);
    route(c);
    s_.endpoint->prepare(c.address);
  }
  std::vector<protocol::node::ExecuteRequest> requests;
  std::vector<std::pair<std::string, std::string>> to; // per request: its node and its `what`
  std::vector<std::vector<std::size_t>> started_by;    // per request, the components it starts
  std::map<std::string, std::size_t> host_of;          // by host address: its request
  std::map<std::size_t, protocol::HostParams> hosts;   // by request
  for (std::size_t i = 0; i < app_->components.size(); ++i) {
    const auto &c = app_->components[i];
    auto node = s_.node_address(c.node);
    if (!node)
      return control::call_error(Status::Unavailable, fmt::format("node {} is gone", c.node));
    if (!is_hosted(c)) {
      requests.push_back(execute_request(c));
      to.emplace_back(*node, c.id);
      started_by.push_back({i});
      continue;
    }
    auto [host, fresh] = host_of.try_emplace(c.host, requests.size());
    if (fresh) {
      requests.push_back(host_request(c));
      to.emplace_back(*node, fmt::format("the component host on {}", c.device));
      started_by.emplace_back();
      hosts[host->second].control_address = c.host;
    }
    hosts[host->second].components.push_back(exec_params(c));
    started_by[host->second].push_back(i);
  }
  for (const auto &[k, params] : hosts)
    requests[k].args = protocol::to_args(params);
  auto bytes = add_packages(requests, started_by);
  if (!bytes)
    return tl::unexpected(bytes.error());
  const auto timeout = s_.call_timeout + delivery_allowance(*bytes);
  std::vector<Call> calls;
  for (std::size_t k = 0; k < requests.size(); ++k) {
    requests[k].budget_ms = timeout.count();
    calls.push_back(call_of<protocol::node::Execute>(to[k].first, requests[k], to[k].second));
  }
  auto replies = call_each_of(*s_.endpoint, calls, timeout);
  // Record every process that did start, even when another failed, so rollback finds it.
  std::vector<CallResult<protocol::node::ExecuteReply>> started;
  for (std::size_t k = 0; k < calls.size(); ++k) {
    started.push_back(control::reply_of<protocol::node::Execute>(std::move(replies[k])));
    if (!started.back())
      continue;
    for (auto i : started_by[k]) {
      app_->components[i].pid = started.back()->pid;
      app_->components[i].log_offset = started.back()->log_offset;
      app_->components[i].state = ComponentState::Executed;
    }
  }
  if (auto ok = first_failure(calls, started); !ok)
    return ok;
  detail_ = fmt::format("{} processes for {} components", calls.size(), app_->components.size());
  if (s_.files != nullptr)
    if (const auto delivered = s_.files->delivered(request_.id); delivered.bytes > 0)
      detail_ += fmt::format("; {:.1f} MB of their files delivered ({:.1f} MB on the wire)",
                             static_cast<double>(delivered.bytes) / 1e6,
                             static_cast<double>(delivered.wire_bytes) / 1e6);
  return {};
}

CallResult<std::uint64_t> ApplicationFactory::Launch::add_packages(
    std::vector<protocol::node::ExecuteRequest> &requests,
    const std::vector<std::vector<std::size_t>> &started_by) const {
  if (s_.files == nullptr)
    return 0;
  std::uint64_t bytes = 0;
  for (std::size_t k = 0; k < requests.size(); ++k) {
    std::vector<PackagedComponent> components;
    for (auto i : started_by[k]) {
      const auto &c = app_->components[i];
      const profile::ComponentPlacement *placement = nullptr;
      instantiation_of(c.id, &placement);
      components.push_back(
          {c.id, request_.profile->softpkg_of(*placement), placement_of(c.id)->implementation});
    }
    auto package = s_.files->package_of(components);
    if (!package)
      return tl::unexpected(package.error());
    for (const auto &f : package->files)
      bytes += f.size;
    requests[k].package = std::move(*package);
    requests[k].launch = request_.id;
  }
  return bytes;
}

std::string ApplicationFactory::Launch::in_package(const std::filesystem::path &file) const {
  return s_.files == nullptr ? file.string() : s_.files->package_path(file);
}

CallResult<void> ApplicationFactory::Launch::await_registration() {
  std::vector<std::string> addresses;
  for (const auto &c : app_->components)
    addresses.push_back(c.address);
  auto ok =
      s_.components->wait_registered(addresses, s_.registration_timeout, request_.cancelled.get());
  if (!ok)
    return ok;
  for (auto &c : app_->components)
    c.state = ComponentState::Registered;
  return {};
}

CallResult<void> ApplicationFactory::Launch::initialize() {
  return call_each<protocol::component::Initialize>([](auto &) { return protocol::Empty{}; });
}

CallResult<void> ApplicationFactory::Launch::configure() {
  std::vector<Call> calls;
  for (const auto &placement : request_.profile->sad->placements) {
    const auto *pkg = request_.profile->softpkg_of(placement);
    for (const auto &ci : placement.instantiations) {
      Json properties = Json::object();
      for (const auto &ref : ci.properties) {
        const auto *definition = pkg->find_property(profile::refid_of(ref));
        if (definition == nullptr || is_execparam_only(*definition) ||
            profile::is_empty_override(*definition, ref))
          continue;
        auto value = profile::bind_property(*definition, ref);
        if (!value && profile::names_unknown_members_only(value.error()))
          continue; // ignored, as the loader warned
        if (!value)
          return control::call_error(Status::BadRequest,
                                     fmt::format("{}: {}", ci.id, value.error().to_string()));
        properties[profile::refid_of(ref)] = profile::to_json(*value);
      }
      if (properties.empty())
        continue;
      calls.push_back(call_of<protocol::component::Configure>(component_of(ci.id)->address,
                                                              {std::move(properties)}, ci.id));
    }
  }
  detail_ = fmt::format("{} components configured", calls.size());
  return call_all(*s_.endpoint, calls, s_.call_timeout);
}

CallResult<void> ApplicationFactory::Launch::start() {
  ApplicationFactory factory(s_);
  // The application is the launch's own until it returns: changes need no lock.
  auto ok = factory.start(*app_, [this](const auto &change) { change(*app_); });
  if (ok)
    detail_ = fmt::format("{} components running", app_->components.size());
  return ok;
}

template <control::Operation Op, typename Request>
CallResult<void> ApplicationFactory::Launch::call_each(Request request) {
  std::vector<Call> calls;
  for (auto &c : app_->components)
    calls.push_back(call_of<Op>(c.address, request(c), c.id));
  return call_all(*s_.endpoint, calls, s_.call_timeout);
}

protocol::ExecParams ApplicationFactory::Launch::exec_params(const ComponentInstance &c) const {
  protocol::ExecParams p;
  p.identifier = c.id;
  p.name_binding = c.usage_name;
  p.profile = in_package(c.spd);
  p.domain = s_.domain_name;
  p.application = app_->name;
  p.control_address = c.address;
  const auto *placement = placement_of(c.id);
  if (is_hosted(c))
    p.library = placement->implementation->code.file.name;
  if (const auto &s = placement->schedule)
    p.schedule = protocol::Schedule{s->cpu, s->priority, s->period, s->budget, s->deadline};
  // Not for a component host: its ten-odd participants joining early slowed its components'
  // registration more than joining at `connect` costs (1000 hosted on 10 nodes: 3.3 s against
  // 2.1 s, docs/measurements.md).
  if (!is_hosted(c) && joins_dds(c))
    p.dds = protocol::kJoinDds;
  p.others = execparams(c);
  return p;
}

protocol::node::ExecuteRequest
ApplicationFactory::Launch::execute_request(const ComponentInstance &c) const {
  const auto *impl = placement_of(c.id)->implementation;
  const auto spd_dir = std::filesystem::path(c.spd).parent_path();
  return {app_->name,
          c.id,
          c.device,
          impl->code.entrypoint.empty() ? impl->code.file.name : impl->code.entrypoint,
          in_package(spd_dir),
          protocol::to_args(exec_params(c)),
          std::nullopt,
          std::nullopt,
          affinity_of(c),
          std::nullopt}; // budget_ms: set when the calls are made
}

protocol::node::ExecuteRequest
ApplicationFactory::Launch::host_request(const ComponentInstance &first) const {
  const auto affinity = affinity_of(first);
  return {app_->name,
          affinity ? fmt::format("ComponentHost_{}_{}", first.device, first.id)
                   : fmt::format("ComponentHost_{}", first.device),
          first.device,
          std::string(protocol::node::kComponentHostProgram),
          "",
          {},
          std::nullopt,
          std::nullopt,
          affinity,
          std::nullopt}; // budget_ms: set when the calls are made
}

std::string ApplicationFactory::Launch::process_name(const ComponentInstance &c) const {
  return is_hosted(c) ? host_request(c).component : c.id;
}

std::optional<protocol::node::AffinityDirective>
ApplicationFactory::Launch::affinity_of(const ComponentInstance &c) const {
  const auto *ci = instantiation_of(c.id);
  if (ci == nullptr || !ci->affinity)
    return std::nullopt;
  return protocol::node::AffinityDirective{std::string(profile::to_string(ci->affinity->directive)),
                                           ci->affinity->value};
}

std::vector<std::pair<std::string, std::string>>
ApplicationFactory::Launch::execparams(const ComponentInstance &c) const {
  std::vector<std::pair<std::string, std::string>> out;
  const profile::ComponentPlacement *placement = nullptr;
  const auto *ci = instantiation_of(c.id, &placement);
  const auto *pkg = request_.profile->softpkg_of(*placement);
  for (const auto &ref : ci->properties) {
    const auto *definition = pkg->find_property(profile::refid_of(ref));
    if (definition == nullptr || !is_execparam_only(*definition) ||
        profile::is_empty_override(*definition, ref))
      continue;
    if (auto value = profile::bind_property(*definition, ref))
      out.emplace_back(profile::refid_of(ref), profile::format_value(*value));
  }
  // REDHAWK's loggingconfig reaches the component as REDHAWK's GPP passes it.
  if (const auto &logging = ci->logging) {
    if (logging->debug_level)
      out.emplace_back("DEBUG_LEVEL", std::to_string(*logging->debug_level));
    if (!logging->uri.empty())
      out.emplace_back("LOGGING_CONFIG_URI", logging->uri);
  }
  return out;
}

const allocator::Placement *
ApplicationFactory::Launch::placement_of(const std::string &instance) const {
  auto it = instances_.find(instance);
  return it != instances_.end() ? it->second.planned : nullptr;
}

const profile::ComponentInstantiation *
ApplicationFactory::Launch::instantiation_of(const std::string &instance,
                                             const profile::ComponentPlacement **placement) const {
  auto it = instances_.find(instance);
  if (it == instances_.end())
    return nullptr;
  if (placement != nullptr)
    *placement = it->second.placement;
  return it->second.instantiation;
}

ComponentInstance *ApplicationFactory::Launch::component_of(const std::string &instance) const {
  auto it = instances_.find(instance);
  return it == instances_.end() || it->second.component == kNone
             ? nullptr
             : &app_->components[it->second.component];
}

void ApplicationFactory::Launch::build_components() {
  const auto &sad = *request_.profile->sad;
  app_->components.reserve(app_->plan.placements.size());
  for (const auto &p : app_->plan.placements) {
    auto &indexed = instances_.at(p.instance);
    indexed.planned = &p;
    indexed.component = app_->components.size();
    const profile::ComponentPlacement *placement = indexed.placement;
    const auto *ci = indexed.instantiation;
    ComponentInstance c;
    c.id = p.instance;
    c.usage_name = ci->usage_name.empty() ? ci->id : ci->usage_name;
    c.node = p.node;
    c.device = p.device;
    c.implementation = p.implementation->id;
    c.address = protocol::component_address(s_.domain_name, app_->name, launch_, p.instance);
    // Hosted components share their device's host; one with an affinity has a host of its own,
    // whose process the affinity is.
    if (p.implementation->code.type == profile::CodeType::SharedLibrary)
      c.host = protocol::host_address(s_.domain_name, app_->name, launch_,
                                      ci->affinity ? p.device + "." + ci->id : p.device);
    c.spd = request_.profile->softpkg_of(*placement)->spd_path.string();
    c.start_order = ci->start_order.value_or(UINT32_MAX);
    c.assembly_controller = sad.assembly_controller == ci->id;
    c.state = ComponentState::Allocated;
    app_->components.push_back(std::move(c));
  }
}

std::size_t ApplicationFactory::Launch::count_instances() const {
  std::size_t n = 0;
  for (const auto &p : request_.profile->sad->placements)
    n += p.instantiations.size();
  return n;
}

std::vector<std::string> ApplicationFactory::Launch::nodes_used() const {
  std::vector<std::string> nodes;
  for (const auto &c : app_->components)
    if (std::find(nodes.begin(), nodes.end(), c.node) == nodes.end())
      nodes.push_back(c.node);
  return nodes;
}

CallResult<std::shared_ptr<Application>>
ApplicationFactory::Launch::fail(const char *step, const control::CallError &error) {
  auto failed = failed_launch(step); // before the rollback forgets the processes
  const auto undone = saga_.roll_back();
  const std::string message =
      fmt::format("launch of {} failed at step '{}': {}{}", app_->name, step, error.message,
                  undone.empty() ? "" : fmt::format("\nrolled back: {}", fmt::join(undone, "; ")));
  spdlog::warn("{}", message);
  progress_({step, "failed", 0});
  if (failed && s_.launch_failed) {
    failed->error = message.substr(0, protocol::application::FailedLaunch::kMaxError);
    s_.launch_failed(std::move(*failed));
  }
  return control::call_error(error.status, message);
}

std::optional<protocol::application::FailedLaunch>
ApplicationFactory::Launch::failed_launch(const char *step) const {
  protocol::application::FailedLaunch failed;
  for (const auto &c : app_->components)
    if (c.pid != 0)
      failed.components.push_back({c.id, c.node, c.pid, process_name(c), c.log_offset});
  if (failed.components.empty())
    return std::nullopt;
  failed.application = app_->name;
  failed.installed = request_.installed;
  failed.launch_id = request_.id;
  failed.step = step;
  failed.failed_at_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                            std::chrono::system_clock::now().time_since_epoch())
                            .count();
  return failed;
}

} // namespace rsca::domain
