#include "domain/application_factory.hpp"

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <future>
#include <map>
#include <set>
#include <unordered_map>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "common/dds_names.hpp"
#include "common/elapsed.hpp"
#include "control/operation.hpp"
#include "dds/port_qos.hpp"
#include "profile/property_binding.hpp"
#include "profile/property_json.hpp"
#include "protocol/component_ops.hpp"
#include "protocol/exec_params.hpp"
#include "protocol/topics.hpp"

namespace rsca::domain {
namespace {

using Clock = std::chrono::steady_clock;
using control::CallResult;
using control::Json;
using control::Status;

// One call of many made at once.
struct Call {
  std::string target;
  std::string operation;
  Json body;
  std::string what; // for messages: "Producer_1"
};

// A call of operation `Op` (protocol/): its request typed, its `what` for messages.
template <control::Operation Op>
Call call_of(std::string target, const typename Op::Request &request, std::string what) {
  return {std::move(target), std::string(Op::name), protocol::encode(request), std::move(what)};
}

// Makes every call at once and waits for all of them; each result in the order of the calls.
// The components of one host get theirs in one request (control::Endpoint::call_all).
std::vector<CallResult<Json>> call_each_of(control::Endpoint &endpoint,
                                           const std::vector<Call> &calls,
                                           std::chrono::milliseconds timeout) {
  std::vector<control::Call> made;
  made.reserve(calls.size());
  for (const auto &c : calls)
    made.push_back({c.target, c.operation, c.body});
  return endpoint.call_all(made, timeout);
}

// The first failure among `results`, prefixed with its call's `what`.
template <typename T>
CallResult<void> first_failure(const std::vector<Call> &calls,
                               const std::vector<CallResult<T>> &results) {
  for (std::size_t i = 0; i < results.size(); ++i)
    if (!results[i])
      return control::call_error(results[i].error().status,
                                 fmt::format("{}: {}", calls[i].what, results[i].error().message));
  return {};
}

CallResult<void> call_all(control::Endpoint &endpoint, const std::vector<Call> &calls,
                          std::chrono::milliseconds timeout) {
  return first_failure(calls, call_each_of(endpoint, calls, timeout));
}

// The processes an application's components run in: the components of a host share its process.
std::set<long> process_ids(const Application &app) {
  std::set<long> pids;
  for (const auto &c : app.components)
    if (c.pid != 0)
      pids.insert(c.pid);
  return pids;
}

bool is_execparam_only(const profile::PropertyDefinition &d) {
  const auto &c = profile::common_of(d);
  return c.has_kind(profile::PropertyKind::ExecParam) &&
         !c.has_kind(profile::PropertyKind::Configure) &&
         !c.has_kind(profile::PropertyKind::Property);
}

} // namespace

// The state of one launch, step by step, and how to undo it.
class ApplicationFactory::Launch {
public:
  Launch(const DomainServices &services, const LaunchRequest &request, const ProgressSink &progress)
      : s_(services), request_(request), progress_(progress), app_(std::make_shared<Application>()),
        launch_(s_.next_launch ? s_.next_launch() : LaunchIdentity{}) {
    app_->name = request.name;
    app_->installed = request.installed;
    app_->profile = request.profile;
    app_->sad = request.profile->sad_path.string();
    for (const auto &placement : request.profile->sad->placements)
      for (const auto &ci : placement.instantiations)
        instances_[ci.id] = {&ci, &placement, nullptr, kNone};
  }

  CallResult<std::shared_ptr<Application>> run() {
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
    app_->state = request_.start ? ApplicationState::Running : ApplicationState::Created;
    spdlog::info("application {} launched: {} components on {}", app_->name,
                 app_->components.size(), fmt::join(nodes_used(), ", "));
    return app_;
  }

private:
  // Wiring problems found while loading (unknown ports, mismatched port types) stop a launch.
  // Wiring problems found while loading (unknown ports, mismatched port types) and event-channel
  // members that could never match the channel's others stop a launch before anything runs.
  CallResult<void> check() {
    if (!request_.profile->warnings.empty()) {
      std::vector<std::string> problems;
      for (const auto &w : request_.profile->warnings)
        problems.push_back(to_string(w));
      return control::call_error(Status::BadRequest, fmt::format("{}", fmt::join(problems, "\n")));
    }
    if (auto unsupported = unsupported_connections(); !unsupported.empty())
      return control::call_error(Status::BadRequest,
                                 fmt::format("{}", fmt::join(unsupported, "\n")));
    if (auto joined = s_.channels->join(channel_members()); !joined)
      return joined;
    joined_channels_ = true;
    detail_ = fmt::format("{} components, {} connections", count_instances(),
                          request_.profile->sad->connections.size());
    return {};
  }

  // Connections rsca cannot make yet, each named with why: refused here rather than left out.
  std::vector<std::string> unsupported_connections() const {
    using Kind = profile::EndpointTarget::Kind;
    std::vector<std::string> out;
    const auto &sad = *request_.profile->sad;
    for (std::size_t i = 0; i < sad.connections.size(); ++i) {
      const auto &c = sad.connections[i];
      const std::string id = connection_id(c, i);
      for (const auto *end : {&c.uses.target, &c.provides.target}) {
        if (end->kind == Kind::FindBy && !end->findby.is_event_channel())
          out.push_back(fmt::format("connection {}: only event channels can be found by findby; "
                                    "\"{}\" is not one",
                                    id, end->findby.name));
      }
      const auto is_device = [](const profile::EndpointTarget &t) {
        return t.kind == Kind::DeviceThatLoadedThisComponent ||
               t.kind == Kind::DeviceUsedByThisComponent;
      };
      if ((c.publishes_to_channel() && is_device(c.uses.target)) ||
          (c.subscribes_to_channel() && is_device(c.provides.target)))
        out.push_back(fmt::format(
            "connection {}: a device port cannot be an event channel member yet: connect it "
            "to a component port",
            id));
      if (c.provides.kind == profile::ProvidesEnd::Kind::SupportedInterface &&
          (c.uses.target.kind != Kind::ComponentInstantiation ||
           c.provides.target.kind != Kind::ComponentInstantiation))
        out.push_back(fmt::format("connection {}: a supported interface connects a component's "
                                  "uses port to another component of the application "
                                  "(componentinstantiationref on both sides), not to a device "
                                  "or a channel",
                                  id));
    }
    return out;
  }

  // This application's publishers and subscribers of event channels, by channel name.
  std::vector<std::pair<std::string, ChannelMember>> channel_members() const {
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

  static std::string connection_id(const profile::Connection &c, std::size_t index) {
    return c.id.empty() ? fmt::format("connection_{}", index + 1) : c.id;
  }

  static const std::string &channel_name(const profile::Connection &c) {
    return c.publishes_to_channel() ? c.provides.target.findby.name : c.uses.target.findby.name;
  }

  CallResult<void> allocate() {
    const allocator::PlanOptions options{request_.strategy.value_or(s_.strategy)};
    auto plan = s_.allocator->allocate(
        allocator::plan_request_of(*request_.profile, request_.assignments), options);
    if (!plan) {
      spdlog::warn("application {} rejected:\n{}", app_->name, allocator::to_string(plan.error()));
      return control::call_error(Status::Rejected, allocator::to_string(plan.error()));
    }
    app_->plan = std::move(*plan);
    allocated_ = true;
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

  // One process per Executable component, and one component host per device for the
  // application's SharedLibrary components on it; all started at once.
  CallResult<void> execute() {
    // Discovery of each component's endpoint starts now and overlaps with its process start.
    for (auto &c : app_->components) {
      s_.components->expect(c.address, c.node);
      if (!c.host.empty())
        s_.endpoint->route(c.address, c.host);
      s_.endpoint->prepare(c.address);
    }
    std::vector<protocol::node::ExecuteRequest> requests;
    std::vector<std::pair<std::string, std::string>> to; // per request: its node and its `what`
    std::vector<std::vector<std::size_t>> started_by;    // per request, the components it starts
    std::map<std::string, std::size_t> host_of;          // by device: its host's request
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
      auto [host, fresh] = host_of.try_emplace(c.device, requests.size());
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
    std::vector<Call> calls;
    for (std::size_t k = 0; k < requests.size(); ++k)
      calls.push_back(call_of<protocol::node::Execute>(to[k].first, requests[k], to[k].second));
    auto replies = call_each_of(*s_.endpoint, calls, s_.call_timeout);
    // Record every process that did start, even when another failed, so rollback finds it.
    std::vector<CallResult<protocol::node::ExecuteReply>> started;
    for (std::size_t k = 0; k < calls.size(); ++k) {
      started.push_back(control::reply_of<protocol::node::Execute>(std::move(replies[k])));
      if (!started.back())
        continue;
      for (auto i : started_by[k]) {
        app_->components[i].pid = started.back()->pid;
        app_->components[i].state = "executed";
      }
    }
    if (auto ok = first_failure(calls, started); !ok)
      return ok;
    detail_ = fmt::format("{} processes for {} components", calls.size(), app_->components.size());
    return {};
  }

  CallResult<void> await_registration() {
    std::vector<std::string> addresses;
    for (const auto &c : app_->components)
      addresses.push_back(c.address);
    auto ok = s_.components->wait_registered(addresses, s_.registration_timeout,
                                             request_.cancelled.get());
    if (!ok)
      return ok;
    for (auto &c : app_->components)
      c.state = "registered";
    return {};
  }

  CallResult<void> initialize() {
    return call_each<protocol::component::Initialize>([](auto &) { return protocol::Empty{}; });
  }

  CallResult<void> configure() {
    std::vector<Call> calls;
    for (const auto &placement : request_.profile->sad->placements) {
      const auto *pkg = request_.profile->softpkg_of(placement);
      for (const auto &ci : placement.instantiations) {
        Json properties = Json::object();
        for (const auto &ref : ci.properties) {
          const auto *definition = pkg->find_property(profile::refid_of(ref));
          if (definition == nullptr || is_execparam_only(*definition))
            continue;
          auto value = profile::bind_property(*definition, ref);
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

  CallResult<void> connect() {
    const auto &sad = *request_.profile->sad;
    std::vector<Call> provides_side, uses_side;
    for (std::size_t i = 0; i < sad.connections.size(); ++i) {
      const auto &c = sad.connections[i];
      ConnectionInstance ci;
      ci.id = connection_id(c, i);
      ci.qos = dds::qos_to_json(c.qos.value_or(profile::ConnectionQos{}));
      ci.topic = c.publishes_to_channel() || c.subscribes_to_channel()
                     ? s_.channels->topic_of(channel_name(c))
                     : protocol::connection_topic(s_.domain_name, app_->name, launch_, ci.id);
      ci.filter = c.filter.value_or("");
      ci.repid = repid_of(c);
      auto uses = resolve_end(ci, c.uses.target, c.uses.port, profile::PortDirection::Uses);
      if (!uses)
        return tl::unexpected(uses.error());
      ci.uses = std::move(*uses);
      if (c.provides.kind == profile::ProvidesEnd::Kind::SupportedInterface) {
        // The component itself, at its control address: no topic, nothing to make on its side.
        ci.topic.clear();
        ci.provides = {c.provides.target.refid, "", "",
                       component_of(c.provides.target.refid)->address};
        uses_side.push_back(interface_call(ci));
        app_->connections.push_back(std::move(ci));
        continue;
      }
      if (c.provides.kind == profile::ProvidesEnd::Kind::Port) {
        auto provides =
            resolve_end(ci, c.provides.target, c.provides.port, profile::PortDirection::Provides);
        if (!provides)
          return tl::unexpected(provides.error());
        ci.provides = std::move(*provides);
      }
      if (!ci.uses.empty())
        uses_side.push_back(connect_call(ci, ci.uses, "uses"));
      if (!ci.provides.empty())
        provides_side.push_back(connect_call(ci, ci.provides, "provides"));
      app_->connections.push_back(std::move(ci));
    }
    // Readers first, so the first samples written find them.
    auto began = Clock::now();
    if (auto ok = call_all(*s_.endpoint, provides_side, s_.call_timeout); !ok)
      return ok;
    const double readers_ms = ms_since(began);
    began = Clock::now();
    if (auto ok = call_all(*s_.endpoint, uses_side, s_.call_timeout); !ok)
      return ok;
    const double writers_ms = ms_since(began);
    began = Clock::now();
    if (auto ok = await_matched(); !ok)
      return ok;
    detail_ =
        fmt::format("{} connections (readers {:.0f} ms, writers {:.0f} ms, matched {:.0f} ms)",
                    app_->connections.size(), readers_ms, writers_ms, ms_since(began));
    return {};
  }

  // One end of a SAD connection: a port of one of this application's components, or of the
  // device that loaded or is used by one of them (checked against what its node announced);
  // nothing for an event channel.
  CallResult<ConnectionEnd> resolve_end(ConnectionInstance &ci,
                                        const profile::EndpointTarget &target,
                                        const std::string &port, profile::PortDirection direction) {
    using Kind = profile::EndpointTarget::Kind;
    if (target.kind == Kind::FindBy)
      return ConnectionEnd{};
    if (target.kind == Kind::ComponentInstantiation)
      return ConnectionEnd{target.refid, port, "", component_of(target.refid)->address};
    auto device = device_of(target);
    if (!device)
      return control::call_error(Status::BadRequest,
                                 fmt::format("connection {}: {}", ci.id, device.error()));
    return device_end(ci, *device, port, direction);
  }

  tl::expected<std::string, std::string> device_of(const profile::EndpointTarget &target) const {
    const auto *placement = placement_of(target.refid);
    if (placement == nullptr)
      return tl::unexpected(fmt::format("no component {} in the application", target.refid));
    if (target.kind == profile::EndpointTarget::Kind::DeviceThatLoadedThisComponent)
      return placement->device;
    for (const auto &used : placement->used_devices)
      if (used.uses_id == target.usesrefid)
        return used.device;
    return tl::unexpected(
        fmt::format("component {} has no usesdevice {}", target.refid, target.usesrefid));
  }

  CallResult<ConnectionEnd> device_end(ConnectionInstance &ci, const std::string &device,
                                       const std::string &port, profile::PortDirection direction) {
    const auto wanted = profile::to_string(direction);
    auto ports = s_.device_ports ? s_.device_ports(device) : std::nullopt;
    const protocol::node::DevicePort *found = nullptr;
    if (ports)
      for (const auto &p : ports->ports)
        if (p.name == port && p.direction == wanted)
          found = &p;
    if (found == nullptr)
      return control::call_error(
          Status::BadRequest,
          fmt::format("connection {}: device {} has no {} port {}", ci.id, device, wanted, port));
    const std::string repid = found->repid;
    if (ci.repid.empty())
      ci.repid = repid;
    if (repid != ci.repid)
      return control::call_error(Status::BadRequest,
                                 fmt::format("connection {}: port type: device port {}.{} carries "
                                             "{}, but the other end carries {}",
                                             ci.id, device, port, repid, ci.repid));
    return ConnectionEnd{"", port, device, ports->address};
  }

  // Waits until every connection made has matched its peers in this application (a channel
  // member: this application's members on the other side), so that nothing a component writes
  // once started is lost to discovery still under way.
  CallResult<void> await_matched() {
    std::map<std::string, protocol::component::AwaitMatchedRequest> awaited; // by address
    auto await = [&](const ConnectionInstance &ci, const ConnectionEnd &end, int peers) {
      if (end.empty() || peers == 0)
        return;
      auto &request = awaited[end.address];
      request.timeout_ms = s_.call_timeout.count();
      request.connections.push_back({end.port, end_key(ci, end), peers, 0});
    };
    for (const auto &ci : app_->connections) {
      if (ci.is_interface())
        continue; // a control address: nothing to discover
      const bool channel = ci.uses.empty() || ci.provides.empty();
      await(ci, ci.uses, channel ? members_on(ci.topic, /*subscribers=*/true) : 1);
      await(ci, ci.provides, channel ? members_on(ci.topic, /*subscribers=*/false) : 1);
    }
    std::vector<Call> calls;
    for (auto &[address, request] : awaited)
      calls.push_back(call_of<protocol::component::AwaitMatched>(address, request, address));
    auto replies = call_each_of(*s_.endpoint, calls, 2 * s_.call_timeout);
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
                                             s_.call_timeout.count(), fmt::join(unmatched, "; ")));
    return {};
  }

  // This application's subscribers (or publishers) on a channel's topic.
  int members_on(const std::string &topic, bool subscribers) const {
    int n = 0;
    for (const auto &ci : app_->connections)
      if (ci.topic == topic && !(subscribers ? ci.provides : ci.uses).empty())
        ++n;
    return n;
  }

  CallResult<void> start() {
    ApplicationFactory factory(s_);
    // The application is the launch's own until it returns: changes need no lock.
    auto ok = factory.start(*app_, [this](const auto &change) { change(*app_); });
    if (ok)
      detail_ = fmt::format("{} components running", app_->components.size());
    return ok;
  }

  // --- helpers ---

  template <control::Operation Op, typename Request>
  CallResult<void> call_each(Request request) {
    std::vector<Call> calls;
    for (auto &c : app_->components)
      calls.push_back(call_of<Op>(c.address, request(c), c.id));
    return call_all(*s_.endpoint, calls, s_.call_timeout);
  }

  Call connect_call(const ConnectionInstance &ci, const ConnectionEnd &end, const char *direction) {
    protocol::component::ConnectRequest request;
    request.connection = end_key(ci, end);
    request.port = end.port;
    request.direction = direction;
    request.topic = ci.topic;
    request.repid = ci.repid;
    request.qos = ci.qos;
    request.filter = std::string_view(direction) == "provides" ? ci.filter : "";
    request.local = in_one_host(ci);
    return call_of<protocol::component::Connect>(end.address, request,
                                                 fmt::format("{} ({})", ci.id, end.name()));
  }

  // A uses port's connection to a component's supported interface: it calls the component's
  // control address.
  Call interface_call(const ConnectionInstance &ci) {
    protocol::component::ConnectRequest request;
    request.connection = end_key(ci, ci.uses);
    request.port = ci.uses.port;
    request.direction = "uses";
    request.repid = ci.repid;
    request.target = ci.provides.address;
    return call_of<protocol::component::Connect>(
        ci.uses.address, request,
        fmt::format("{} ({} -> {})", ci.id, ci.uses.name(), ci.provides.name()));
  }

  // Both ends are components of one component host: the connection bypasses DDS.
  bool in_one_host(const ConnectionInstance &ci) const {
    if (ci.uses.component.empty() || ci.provides.component.empty())
      return false;
    const auto *uses = component_of(ci.uses.component);
    const auto *provides = component_of(ci.provides.component);
    return uses != nullptr && provides != nullptr && !uses->host.empty() &&
           uses->host == provides->host;
  }

  std::string repid_of(const profile::Connection &c) const {
    for (const auto *end : {&c.uses.target, &c.provides.target}) {
      if (end->kind != profile::EndpointTarget::Kind::ComponentInstantiation)
        continue;
      const profile::ComponentPlacement *placement = nullptr;
      if (instantiation_of(end->refid, &placement) == nullptr)
        continue;
      const auto *pkg = request_.profile->softpkg_of(*placement);
      if (pkg == nullptr || !pkg->scd)
        continue;
      const bool uses = end == &c.uses.target;
      if (!uses && c.provides.kind != profile::ProvidesEnd::Kind::Port)
        continue; // a supported interface's repid, not a port
      const auto *port = pkg->scd->find_port(uses ? c.uses.port : c.provides.port,
                                             uses ? profile::PortDirection::Uses
                                                  : profile::PortDirection::Provides);
      if (port != nullptr)
        return port->repid;
    }
    return {};
  }

  // The exec parameters of a component (protocol/exec_params.hpp); a hosted one's name the
  // library its host loads, as the SPD names it (the host resolves it, as a GPP resolves an
  // entry point).
  protocol::ExecParams exec_params(const ComponentInstance &c) const {
    protocol::ExecParams p;
    p.identifier = c.id;
    p.name_binding = c.usage_name;
    p.profile = c.spd;
    p.domain = s_.domain_name;
    p.application = app_->name;
    p.control_address = c.address;
    const auto *placement = placement_of(c.id);
    if (is_hosted(c))
      p.library = placement->implementation->code.file.name;
    if (const auto &s = placement->schedule)
      p.schedule = protocol::Schedule{s->cpu, s->priority, s->period, s->budget, s->deadline};
    p.others = execparams(c);
    return p;
  }

  static bool is_hosted(const ComponentInstance &c) { return !c.host.empty(); }

  protocol::node::ExecuteRequest execute_request(const ComponentInstance &c) const {
    const auto *impl = placement_of(c.id)->implementation;
    const auto spd_dir = std::filesystem::path(c.spd).parent_path();
    return {app_->name,
            c.id,
            c.device,
            impl->code.entrypoint.empty() ? impl->code.file.name : impl->code.entrypoint,
            spd_dir.string(),
            protocol::to_args(exec_params(c))};
  }

  // A component host's process at its own address; its components' exec parameters follow.
  protocol::node::ExecuteRequest host_request(const ComponentInstance &first) const {
    return {app_->name,   fmt::format("ComponentHost_{}", first.device),
            first.device, "rsca-component-host",
            "",           {}};
  }

  // The component's execparam-only properties, as its SAD instantiation sets them.
  std::vector<std::pair<std::string, std::string>> execparams(const ComponentInstance &c) const {
    std::vector<std::pair<std::string, std::string>> out;
    const profile::ComponentPlacement *placement = nullptr;
    const auto *ci = instantiation_of(c.id, &placement);
    const auto *pkg = request_.profile->softpkg_of(*placement);
    for (const auto &ref : ci->properties) {
      const auto *definition = pkg->find_property(profile::refid_of(ref));
      if (definition == nullptr || !is_execparam_only(*definition))
        continue;
      if (auto value = profile::bind_property(*definition, ref))
        out.emplace_back(profile::refid_of(ref), profile::format_value(*value));
    }
    return out;
  }

  const allocator::Placement *placement_of(const std::string &instance) const {
    auto it = instances_.find(instance);
    return it != instances_.end() ? it->second.planned : nullptr;
  }

  // The SAD's instantiation of that id, and the placement holding it; nullptr when none.
  const profile::ComponentInstantiation *
  instantiation_of(const std::string &instance,
                   const profile::ComponentPlacement **placement = nullptr) const {
    auto it = instances_.find(instance);
    if (it == instances_.end())
      return nullptr;
    if (placement != nullptr)
      *placement = it->second.placement;
    return it->second.instantiation;
  }

  ComponentInstance *component_of(const std::string &instance) const {
    auto it = instances_.find(instance);
    return it == instances_.end() || it->second.component == kNone
               ? nullptr
               : &app_->components[it->second.component];
  }

  void build_components() {
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
      if (p.implementation->code.type == profile::CodeType::SharedLibrary)
        c.host = protocol::host_address(s_.domain_name, app_->name, launch_, p.device);
      c.spd = request_.profile->softpkg_of(*placement)->spd_path.string();
      c.start_order = ci->start_order.value_or(UINT32_MAX);
      c.assembly_controller = sad.assembly_controller == ci->id;
      c.state = "allocated";
      app_->components.push_back(std::move(c));
    }
  }

  std::size_t count_instances() const {
    std::size_t n = 0;
    for (const auto &p : request_.profile->sad->placements)
      n += p.instantiations.size();
    return n;
  }

  std::vector<std::string> nodes_used() const {
    std::vector<std::string> nodes;
    for (const auto &c : app_->components)
      if (std::find(nodes.begin(), nodes.end(), c.node) == nodes.end())
        nodes.push_back(c.node);
    return nodes;
  }

  CallResult<std::shared_ptr<Application>> fail(const char *step, const control::CallError &error) {
    const std::string undone = roll_back();
    const std::string message =
        fmt::format("launch of {} failed at step '{}': {}{}", app_->name, step, error.message,
                    undone.empty() ? "" : fmt::format("\nrolled back: {}", undone));
    spdlog::warn("{}", message);
    progress_({step, "failed", 0});
    return control::call_error(error.status, message);
  }

  // Undoes what the launch did: processes first, then the allocation.
  std::string roll_back() {
    std::vector<std::string> undone;
    std::vector<std::string> devices;
    for (const auto &p : app_->plan.placements)
      if (std::find(devices.begin(), devices.end(), p.device) == devices.end())
        devices.push_back(p.device);
    ApplicationFactory factory(s_);
    const std::size_t started = process_ids(*app_).size();
    if (joined_channels_) {
      const auto destroyed = s_.channels->leave(app_->name);
      undone.push_back(destroyed.empty() ? "event channel memberships withdrawn"
                                         : fmt::format("event channels {} destroyed",
                                                       fmt::join(destroyed, ", ")));
    }
    if (started > 0) {
      factory.release(*app_);
      undone.push_back(fmt::format("{} process{} terminated", started, started == 1 ? "" : "es"));
    } else if (allocated_) {
      s_.allocator->release(app_->plan);
    }
    if (allocated_) {
      undone.push_back(fmt::format("allocations on {} released", fmt::join(devices, ", ")));
    }

    return fmt::format("{}", fmt::join(undone, "; "));
  }

  // Per instance id: the SAD's instantiation and placement, the allocator's placement and the
  // component (an index into app_->components), so that per-component and per-connection
  // look-ups keep a launch linear in its size.
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  struct Instance {
    const profile::ComponentInstantiation *instantiation = nullptr;
    const profile::ComponentPlacement *placement = nullptr;
    const allocator::Placement *planned = nullptr;
    std::size_t component = kNone;
  };
  std::unordered_map<std::string, Instance> instances_;

  const DomainServices &s_;
  const LaunchRequest &request_;
  const ProgressSink &progress_;
  std::shared_ptr<Application> app_;
  bool allocated_ = false;
  bool joined_channels_ = false;
  LaunchIdentity launch_; // addresses and topics carry it
  std::string detail_;
};

CallResult<std::shared_ptr<Application>> ApplicationFactory::create(const LaunchRequest &request,
                                                                    const ProgressSink &progress) {
  return Launch(services_, request, progress).run();
}

namespace {

bool exited(const ComponentInstance &c) {
  return c.state == "exited";
}

// Marks the components `ids` names as `state`, except those that exited meanwhile.
void mark(Application &app, const std::vector<std::string> &ids, const char *state) {
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
    apply([&ids](Application &a) { mark(a, ids, "running"); });
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
    mark(a, stopped, "stopped");
    a.state = ApplicationState::Stopped;
  });
  return first_failure(calls, replies);
}

// Devices outlive the application: their ends of its connections go first.
void ApplicationFactory::disconnect_devices(const Application &app) {
  std::vector<Call> calls;
  for (const auto &ci : app.connections)
    for (const auto *end : {&ci.uses, &ci.provides})
      if (!end->device.empty())
        calls.push_back(
            call_of<protocol::component::Disconnect>(end->address, {end_key(ci, *end), end->port},
                                                     fmt::format("{} ({})", ci.id, end->name())));
  const auto replies = call_each_of(*services_.endpoint, calls, services_.call_timeout);
  for (std::size_t i = 0; i < replies.size(); ++i)
    if (!replies[i])
      spdlog::warn("application {}: disconnecting device end of {} failed: {}", app.name,
                   calls[i].what, replies[i].error().message);
}

CallResult<std::vector<std::string>> ApplicationFactory::release(Application &app) {
  disconnect_devices(app);
  std::vector<Call> releases;
  for (auto &c : app.components)
    if (c.pid != 0 && services_.components->registered(c.address))
      releases.push_back(call_of<protocol::component::Release>(c.address, {}, c.id));
  const auto released = call_each_of(*services_.endpoint, releases, services_.call_timeout);
  std::vector<std::string> unconfirmed;
  for (std::size_t i = 0; i < released.size(); ++i) {
    if (released[i])
      continue;
    spdlog::warn("{} of application {} did not confirm its release ({}); its node terminates it",
                 releases[i].what, app.name, released[i].error().message);
    unconfirmed.push_back(releases[i].what);
  }
  // Whatever is still running is terminated by its node; the node reaps every process.
  std::vector<Call> terminations;
  std::set<long> terminated_pids; // the components of a host share its process
  for (auto &c : app.components) {
    if (c.pid == 0 || !terminated_pids.insert(c.pid).second)
      continue;
    auto node = services_.node_address(c.node);
    if (node)
      terminations.push_back(call_of<protocol::node::Terminate>(*node, {c.pid}, c.id));
  }
  auto terminated = call_each_of(*services_.endpoint, terminations, services_.call_timeout);
  for (auto &c : app.components) {
    services_.components->forget(c.address);
    services_.endpoint->forget(c.address);
    if (!c.host.empty())
      services_.endpoint->forget(c.host);
    c.state = "released";
    c.pid = 0;
  }
  services_.allocator->release(app.plan);
  app.plan = {};
  services_.channels->leave(app.name);
  // A component whose node is gone cannot be terminated by it, and is gone with it.
  for (std::size_t i = 0; i < terminated.size(); ++i)
    if (!terminated[i] && terminated[i].error().status != Status::Unavailable &&
        terminated[i].error().status != Status::NotFound)
      return tl::unexpected(first_failure(terminations, terminated).error());
  return unconfirmed;
}

} // namespace rsca::domain
