#include "component/host.hpp"

#include <algorithm>
#include <tuple>

#include <fmt/format.h>
#include <pthread.h>
#include <sched.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstring>

#include "dds/port_qos.hpp"

namespace rsca::component::detail {

using control::Status;

namespace {

// REDHAWK's DEBUG_LEVEL: 0 fatal, 1 error, 2 warn, 3 info, 4 debug, 5 trace.
std::optional<spdlog::level::level_enum> debug_level(const std::string &text) {
  constexpr spdlog::level::level_enum kLevels[] = {spdlog::level::critical, spdlog::level::err,
                                                   spdlog::level::warn,     spdlog::level::info,
                                                   spdlog::level::debug,    spdlog::level::trace};
  if (text.size() != 1 || text[0] < '0' || text[0] > '5')
    return std::nullopt;
  return kLevels[text[0] - '0'];
}

// Exec parameters a REDHAWK GPP passes that are not properties.
bool is_redhawk_extra(const std::string &key) {
  return key == "LOGGING_CONFIG_URI" || key == "NIC" ||
         key == "RH::GPP::MODIFIED_CPU_RESERVATION_VALUE";
}

// Every PRF definition of the package: the SPD's PRF, then the implementations' (first wins).
std::vector<profile::PropertyDefinition> definitions_of(const profile::ResolvedSoftPkg &softpkg) {
  std::vector<profile::PropertyDefinition> out;
  auto add = [&out](const std::shared_ptr<const profile::Properties> &prf) {
    if (!prf)
      return;
    for (const auto &d : prf->properties) {
      const auto &id = profile::common_of(d).id;
      const bool known = std::any_of(out.begin(), out.end(),
                                     [&](const auto &o) { return profile::common_of(o).id == id; });
      if (!known)
        out.push_back(d);
    }
  };
  add(softpkg.properties);
  for (const auto &implementation : softpkg.implementations)
    add(implementation.properties);
  return out;
}

CallResult<std::string> string_field(const Json &body, const char *key) {
  auto it = body.find(key);
  if (it == body.end() || !it->is_string() || it->get_ref<const std::string &>().empty())
    return control::call_error(Status::BadRequest,
                               fmt::format("the request needs \"{}\", a non-empty string", key));
  return it->get<std::string>();
}

CallResult<std::vector<std::string>> ids_field(const Json &body) {
  auto it = body.find("ids");
  if (it == body.end() || it->is_null())
    return std::vector<std::string>{};
  if (!it->is_array())
    return control::call_error(Status::BadRequest, "\"ids\" must be an array of property ids");
  std::vector<std::string> ids;
  for (const auto &id : *it) {
    if (!id.is_string())
      return control::call_error(Status::BadRequest, "\"ids\" must be an array of property ids");
    ids.push_back(id.get<std::string>());
  }
  return ids;
}

std::string first_message(const Error &error) {
  return error.diagnostics().empty() ? std::string("unknown error")
                                     : error.diagnostics().front().message;
}

} // namespace

Expected<void> Host::check_ports() const {
  const auto &scd = softpkg_->scd;
  Error error;
  auto fail = [&](std::string message) {
    error.add({{softpkg_->spd_path.string(), 0, 0}, "binding", std::move(message)});
  };
  for (const auto &port : c().ports_) {
    if (find_port(port->name()) != port.get())
      fail(fmt::format("the component declares port \"{}\" twice", port->name()));
    const auto *definition = scd ? scd->find_port(port->name(), port->direction()) : nullptr;
    if (definition == nullptr) {
      fail(fmt::format("the component has {} port \"{}\", which its SCD does not declare",
                       profile::to_string(port->direction()), port->name()));
      continue;
    }
    const auto type = port::port_type_for_repid(definition->repid);
    if (type != port->type())
      fail(fmt::format("port \"{}\" carries {}, but its SCD repid is {}", port->name(),
                       port::to_string(port->type()), definition->repid));
  }
  for (const auto &port : c().resource_ports_) {
    if (find_resource_port(port->name()) != port.get() || find_port(port->name()) != nullptr)
      fail(fmt::format("the component declares port \"{}\" twice", port->name()));
    const auto *definition =
        scd ? scd->find_port(port->name(), profile::PortDirection::Uses) : nullptr;
    if (definition == nullptr)
      fail(fmt::format("the component has uses port \"{}\", which its SCD does not declare",
                       port->name()));
    else if (!profile::is_control_interface(definition->repid))
      fail(fmt::format("port \"{}\" calls a component's CF interface, but its SCD repid is {}",
                       port->name(), definition->repid));
  }
  if (!error.empty())
    return tl::unexpected(std::move(error));
  for (const auto &definition : scd ? scd->ports : std::vector<profile::PortDefinition>{})
    if (find_port(definition.name) == nullptr && find_resource_port(definition.name) == nullptr)
      log().warn("SCD port \"{}\" has no implementation in the component: it cannot be connected",
                 definition.name);
  return {};
}

Expected<void> Host::prepare(const std::vector<std::pair<std::string, std::string>> &execparams) {
  auto lock = c().lock_properties();
  auto loaded = c().properties_.load(definitions_of(*softpkg_));
  auto ports = check_ports();
  if (!loaded || !ports) {
    Error error;
    if (!loaded)
      error.append(loaded.error());
    if (!ports)
      error.append(ports.error());
    return tl::unexpected(std::move(error));
  }
  for (const auto &[key, value] : execparams) {
    if (key == "DEBUG_LEVEL") {
      if (auto level = debug_level(value))
        log().set_level(*level);
      continue;
    }
    if (c().properties_.find(key) == nullptr) {
      if (!is_redhawk_extra(key))
        log().warn("ignoring exec parameter \"{}\": no such property", key);
      continue;
    }
    if (auto applied = c().properties_.apply_text(key, value); !applied)
      return make_error({softpkg_->spd_path.string(), 0, 0}, "execparam", applied.error());
  }
  return {};
}

Expected<void> Host::open(std::shared_ptr<dds::Participant> participant,
                          std::shared_ptr<control::Endpoint> endpoint,
                          std::function<void()> on_released, control::EndpointOptions options) {
  participant_ = std::move(participant);
  on_released_ = std::move(on_released);
  address_ = c().context().control_address;
  auto loop = ReceiveLoop::start([this] { poll_ports(); });
  if (!loop)
    return tl::unexpected(loop.error());
  loop_ = std::move(*loop);
  configure_thread(loop_->thread(), "rx:");
  if (!endpoint) {
    auto own = control::Endpoint::open(participant_, address_, std::move(options));
    if (!own)
      return tl::unexpected(own.error());
    endpoint = std::move(*own);
  }
  endpoint_ = std::move(endpoint);
  serve("component.initialize", &Host::op_initialize);
  serve("component.configure", &Host::op_configure);
  serve("component.query", &Host::op_query);
  serve("component.connect", &Host::op_connect);
  serve("component.disconnect", &Host::op_disconnect);
  serve("component.start", &Host::op_start);
  serve("component.stop", &Host::op_stop);
  serve("component.status", &Host::op_status);
  serve("component.await_matched", &Host::op_await_matched);
  serve("component.release", &Host::op_release);
  // The domain calls next (initialize): the way back to it is made before it asks.
  endpoint_->prepare_replies(domain_address());
  std::lock_guard lock(lifecycle_);
  return endpoint_->announce(address_, "component", announcement());
}

void Host::close() {
  if (endpoint_) {
    endpoint_->withdraw(address_);
    endpoint_->stop_serving(address_); // waits for running handlers
  }
  stop_service();
  if (loop_)
    loop_->stop();
  // Only once the receive thread has stopped: it reports connection problems through the
  // endpoint (ThreadSanitizer saw it read endpoint_ while close cleared it, then call through
  // null: a consumer crashed as it exited).
  endpoint_.reset();
  component_.reset(); // its ports detach from the stopped loop
  loop_.reset();
  participant_.reset();
}

// Runs `op` for `operation`: exceptions become errors.
void Host::serve(const std::string &operation, Operation op) {
  endpoint_->on(
      address_, operation,
      [this, op](const Json &body, const control::RequestContext &context) -> CallResult<Json> {
        log().debug("{} from {}", context.operation, context.sender);
        try {
          return (this->*op)(body, context);
        } catch (const nlohmann::json::exception &e) {
          return control::call_error(Status::BadRequest, e.what());
        } catch (const std::exception &e) {
          return control::call_error(Status::Failed, e.what());
        }
      });
}

Expected<void> Host::bring_up(const Json &properties) {
  const std::string where = softpkg_->spd_path.string();
  for (const auto &[name, operation, body] :
       {std::tuple{"initialize", &Host::op_initialize, Json::object()},
        std::tuple{"configure", &Host::op_configure, Json{{"properties", properties}}},
        std::tuple{"start", &Host::op_start, Json::object()}}) {
    if (std::string_view(name) == "configure" && properties.empty())
      continue;
    if (auto ok = (this->*operation)(body, control::RequestContext{}); !ok)
      return make_error({where, 0, 0}, name, ok.error().message);
  }
  return {};
}

Json Host::ports_json() const {
  Json ports = Json::array();
  for (const auto &port : c().ports_) {
    const auto *definition =
        softpkg_->scd ? softpkg_->scd->find_port(port->name(), port->direction()) : nullptr;
    ports.push_back(
        {{"name", port->name()},
         {"direction", profile::to_string(port->direction())},
         {"repid", definition ? definition->repid : std::string(port::repid_of(port->type()))}});
  }
  return ports;
}

Json Host::announcement() const {
  return {{"id", c().identifier()},
          {"name", c().name()},
          {"application", c().context().application},
          {"pid", ::getpid()},
          {"state", to_string(c().state())},
          {"ports", ports_json()}};
}

// Called with lifecycle_ held.
void Host::set_state(State state) {
  c().state_ = state;
  log().info("{}", to_string(state));
  if (state == State::Released || !endpoint_)
    return;
  if (auto ok = endpoint_->announce(address_, "component", announcement()); !ok)
    log().warn("updating the announcement failed: {}", ok.error().to_string());
}

PortBase *Host::find_port(const std::string &name) const {
  for (const auto &port : c().ports_)
    if (port->name() == name)
      return port.get();
  return nullptr;
}

void Host::poll_ports() {
  const bool deliver = delivering_.load();
  for (const auto &port : c().ports_)
    if (port->direction() == profile::PortDirection::Provides)
      port->take_all(deliver);
  // Problems are looked for every kProblemCheck at most, not at every sample (ports.cpp says why).
  const auto now = std::chrono::steady_clock::now();
  if (now - last_problem_check_ < kProblemCheck)
    return;
  last_problem_check_ = now;
  std::vector<ConnectionProblem> problems;
  for (const auto &port : c().ports_)
    for (auto &p : port->take_problems())
      problems.push_back(std::move(p));
  report_problems(std::move(problems));
}

// The receive thread wakes now and then only while a connection has problems to look for: a
// host of a thousand components would otherwise wake ten thousand times a second for nothing.
void Host::watch_connections() {
  if (!loop_)
    return;
  loop_->set_watching(std::any_of(c().ports_.begin(), c().ports_.end(),
                                  [](const auto &port) { return port->watched(); }));
}

// The domain daemon's address (DOMAIN_NAME, rsca when not given).
std::string Host::domain_address() const {
  const auto &domain = c().context().domain;
  return (domain.empty() ? std::string("rsca") : domain) + "/domain";
}

void Host::report_problems(std::vector<ConnectionProblem> problems) {
  for (const auto &p : problems)
    unreported_problems_[{p.connection, p.problem}] += p.count;
  const auto now = std::chrono::steady_clock::now();
  if (unreported_problems_.empty() || now - last_problem_report_ < std::chrono::seconds(1))
    return;
  last_problem_report_ = now;
  for (const auto &[key, count] : unreported_problems_) {
    log().warn("connection {}: {} ({} times)", key.first, key.second, count);
    // Not waited for: the receive thread never blocks on the domain.
    endpoint_->call(domain_address(), "domain.connection_problem",
                    Json{{"application", c().context().application},
                         {"component", c().context().name},
                         {"connection", key.first},
                         {"problem", key.second},
                         {"count", count}},
                    std::chrono::seconds(2));
  }
  unreported_problems_.clear();
}

// ---- The service thread

void Host::start_service() {
  {
    std::lock_guard lock(service_mutex_);
    service_stopping_ = false;
  }
  service_thread_ = std::thread([this] { service_loop(); });
  configure_thread(service_thread_, "svc:");
}

// Names the component's own threads after it, and runs them on the CPU admission chose for a
// periodic component: in a component host the process's other threads are shared, these are
// the component's.
void Host::configure_thread(std::thread &thread, std::string_view prefix) {
  const std::string name = fmt::format("{}{}", prefix, c().name()).substr(0, 15);
  pthread_setname_np(thread.native_handle(), name.c_str());
  const auto &schedule = c().context().schedule;
  if (!schedule)
    return;
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(schedule->cpu, &set);
  if (int rc = pthread_setaffinity_np(thread.native_handle(), sizeof(set), &set); rc != 0)
    log().warn("cannot run thread {} on cpu {} as admitted: {}", name, schedule->cpu,
               std::strerror(rc));
}

void Host::stop_service() {
  {
    std::lock_guard lock(service_mutex_);
    service_stopping_ = true;
  }
  service_wake_.notify_all();
  if (service_thread_.joinable())
    service_thread_.join();
}

void Host::service_loop() {
  auto next = Clock::now();
  for (;;) {
    std::optional<Clock::duration> delay;
    {
      auto lock = c().lock_properties();
      try {
        delay = c().service();
      } catch (const std::exception &e) {
        log().error("service() failed: {}; it is not called again until the next start", e.what());
        return;
      }
    }
    if (!delay)
      return;
    const auto period = std::max(*delay, Clock::duration::zero());
    next += period;
    if (const auto now = Clock::now(); next + period < now)
      next = now; // more than a period late: skip ahead rather than burst
    std::unique_lock lock(service_mutex_);
    if (service_wake_.wait_until(lock, next, [this] { return service_stopping_; }))
      return;
  }
}

// ---- Operations

CallResult<Json> Host::op_initialize(const Json &, const control::RequestContext &) {
  std::lock_guard lock(lifecycle_);
  if (c().state() == State::Released)
    return control::call_error(Status::Unavailable, "the component is released");
  if (c().state() != State::Loaded)
    return Json::object(); // already initialized
  {
    auto properties = c().lock_properties();
    if (auto ok = c().initialize(); !ok)
      return tl::unexpected(ok.error());
  }
  set_state(State::Initialized);
  return Json::object();
}

CallResult<Json> Host::op_configure(const Json &body, const control::RequestContext &) {
  auto it = body.find("properties");
  if (it == body.end())
    return control::call_error(Status::BadRequest, "the request needs \"properties\"");
  std::lock_guard lock(lifecycle_);
  if (c().state() == State::Released)
    return control::call_error(Status::Unavailable, "the component is released");
  auto properties = c().lock_properties();
  auto notifications = c().properties_.configure(*it);
  if (!notifications)
    return tl::unexpected(notifications.error());
  for (const auto &notify : *notifications) {
    try {
      notify();
    } catch (const std::exception &e) {
      log().error("a property change callback failed: {}", e.what());
    }
  }
  log().info("configured {}", it->dump());
  return Json::object();
}

CallResult<Json> Host::op_query(const Json &body, const control::RequestContext &) {
  auto ids = ids_field(body);
  if (!ids)
    return tl::unexpected(ids.error());
  auto properties = c().lock_properties();
  auto values = c().properties_.query(*ids);
  if (!values)
    return tl::unexpected(values.error());
  return Json{{"properties", std::move(*values)}};
}

// A connection of a uses port of a CF control interface to another component's supported
// interface: the port keeps that component's control address ("target").
CallResult<Json> Host::connect_resource_port(ResourceUsesPort &port, const Json &body) {
  auto connection = string_field(body, "connection");
  auto target = string_field(body, "target");
  for (const auto *field : {&connection, &target})
    if (!*field)
      return tl::unexpected(field->error());
  if (body.value("direction", "uses") != "uses")
    return control::call_error(Status::BadRequest,
                               fmt::format("port \"{}\" is a uses port", port.name()));
  std::lock_guard lock(lifecycle_);
  if (c().state() == State::Released)
    return control::call_error(Status::Unavailable, "the component is released");
  port.connect(*connection, *target, endpoint_);
  log().info("port {}: connection {} to the component at {}", port.name(), *connection, *target);
  return Json::object();
}

ResourceUsesPort *Host::find_resource_port(const std::string &name) const {
  for (const auto &port : c().resource_ports_)
    if (port->name() == name)
      return port.get();
  return nullptr;
}

CallResult<Json> Host::op_connect(const Json &body, const control::RequestContext &) {
  if (auto *resource = find_resource_port(body.value("port", "")))
    return connect_resource_port(*resource, body);
  auto connection = string_field(body, "connection");
  auto port_name = string_field(body, "port");
  auto direction = string_field(body, "direction");
  auto topic = string_field(body, "topic");
  auto repid = string_field(body, "repid");
  for (const auto *field : {&connection, &port_name, &direction, &topic, &repid})
    if (!*field)
      return tl::unexpected(field->error());
  PortBase *port = find_port(*port_name);
  if (port == nullptr)
    return control::call_error(Status::NotFound, fmt::format("no port \"{}\"", *port_name));
  if (*direction != profile::to_string(port->direction()))
    return control::call_error(Status::BadRequest,
                               fmt::format("port \"{}\" is a {} port, not {}", *port_name,
                                           profile::to_string(port->direction()), *direction));
  if (port::port_type_for_repid(*repid) != port->type())
    return control::call_error(Status::BadRequest,
                               fmt::format("port \"{}\" carries {}, which {} does not", *port_name,
                                           port::to_string(port->type()), *repid));
  auto qos = dds::qos_from_json(body.contains("qos") ? body.at("qos") : Json::object());
  if (!qos)
    return control::call_error(Status::BadRequest, first_message(qos.error()));
  const std::string filter_text = body.value("filter", "");
  std::optional<ContentFilter> filter;
  if (!filter_text.empty()) {
    if (port->direction() != profile::PortDirection::Provides)
      return control::call_error(Status::BadRequest,
                                 "only a provides port filters what it receives");
    auto parsed = ContentFilter::parse(filter_text);
    if (!parsed)
      return control::call_error(Status::BadRequest,
                                 fmt::format("filter \"{}\": {}", filter_text, parsed.error()));
    filter = std::move(*parsed);
  }
  std::lock_guard lock(lifecycle_);
  if (c().state() == State::Released)
    return control::call_error(Status::Unavailable, "the component is released");
  const bool local = body.value("local", false); // the other end is in this process
  if (auto ok = port->connect(participant_->get(), loop_.get(), *connection, *topic, qos->get(),
                              std::move(filter), local);
      !ok)
    return control::call_error(Status::Failed, first_message(ok.error()));
  watch_connections();
  log().info("port {}: connection {} on {}topic \"{}\"{}", *port_name, *connection,
             local ? "in-host " : "", *topic,
             filter_text.empty() ? "" : fmt::format(" with filter \"{}\"", filter_text));
  return Json::object();
}

CallResult<Json> Host::op_disconnect(const Json &body, const control::RequestContext &) {
  auto connection = string_field(body, "connection");
  if (!connection)
    return tl::unexpected(connection.error());
  auto port_name = string_field(body, "port");
  if (!port_name)
    return tl::unexpected(port_name.error());
  if (auto *resource = find_resource_port(*port_name)) {
    if (!resource->disconnect(*connection))
      return control::call_error(
          Status::NotFound,
          fmt::format("port \"{}\" has no connection \"{}\"", *port_name, *connection));
    log().info("port {}: connection {} removed", *port_name, *connection);
    return Json::object();
  }
  PortBase *port = find_port(*port_name);
  if (port == nullptr)
    return control::call_error(Status::NotFound, fmt::format("no port \"{}\"", *port_name));
  std::lock_guard lock(lifecycle_);
  if (!port->disconnect(*connection))
    return control::call_error(Status::NotFound, fmt::format("port \"{}\" has no connection \"{}\"",
                                                             *port_name, *connection));
  watch_connections();
  log().info("port {}: connection {} removed", *port_name, *connection);
  return Json::object();
}

CallResult<Json> Host::op_start(const Json &, const control::RequestContext &) {
  std::lock_guard lock(lifecycle_);
  switch (c().state()) {
  case State::Released:
    return control::call_error(Status::Unavailable, "the component is released");
  case State::Loaded:
    return control::call_error(Status::Rejected, "the component is not initialized");
  case State::Started:
    return Json::object();
  default:
    break;
  }
  {
    auto properties = c().lock_properties();
    if (auto ok = c().start(); !ok)
      return tl::unexpected(ok.error());
  }
  delivering_ = true;
  start_service();
  set_state(State::Started);
  return Json::object();
}

// Called with lifecycle_ held, when started: the service thread and port callbacks stop before
// the stop hook runs.
void Host::stop_component() {
  stop_service();
  delivering_ = false;
  for (const auto &port : c().ports_)
    port->quiesce();
}

CallResult<Json> Host::op_stop(const Json &, const control::RequestContext &) {
  std::lock_guard lock(lifecycle_);
  if (c().state() != State::Started)
    return Json::object();
  stop_component();
  Result result;
  {
    auto properties = c().lock_properties();
    result = c().stop();
  }
  set_state(State::Stopped);
  if (!result)
    return tl::unexpected(result.error());
  return Json::object();
}

CallResult<Json> Host::op_status(const Json &, const control::RequestContext &) {
  Json ports = Json::array();
  for (const auto &port : c().ports_) {
    Json connections = Json::array();
    for (const auto &s : port->status())
      connections.push_back({{"connection", s.connection},
                             {"topic", s.topic},
                             {"matched", s.matched},
                             {"samples", s.samples},
                             {"filtered", s.filtered},
                             {"deadline_missed", s.deadline_missed},
                             {"in_host", s.in_host}});
    ports.push_back({{"name", port->name()},
                     {"direction", profile::to_string(port->direction())},
                     {"connections", std::move(connections)}});
  }
  for (const auto &port : c().resource_ports_) {
    Json connections = Json::array();
    for (const auto &[connection, target] : port->targets())
      connections.push_back(
          {{"connection", connection}, {"target", target.address}, {"calls", target.calls}});
    ports.push_back(
        {{"name", port->name()}, {"direction", "uses"}, {"connections", std::move(connections)}});
  }
  return Json{{"state", to_string(c().state())}, {"ports", std::move(ports)}};
}

// Waits, bounded, until each named connection has matched the peers the domain expects: a
// launch starts its components only once their first samples will find their readers. Replies
// with what each connection matched; "complete" says whether all got there in time.
// The time counts from the request's arrival: in a batch for a whole host, the awaits of one
// component after another all end within the caller's timeout.
CallResult<Json> Host::op_await_matched(const Json &body, const control::RequestContext &context) {
  struct Awaited {
    const PortBase *port;
    std::string connection;
    std::int32_t peers;
    std::int32_t matched = 0;
  };
  std::vector<Awaited> awaited;
  for (const auto &entry : body.value("connections", Json::array())) {
    const PortBase *port = find_port(entry.value("port", ""));
    if (port == nullptr)
      return control::call_error(Status::NotFound,
                                 fmt::format("no port \"{}\"", entry.value("port", "")));
    awaited.push_back({port, entry.value("connection", ""), entry.value("peers", 1)});
  }
  const auto deadline =
      context.received + std::chrono::milliseconds(body.value("timeout_ms", 2000));
  auto all_matched = [&awaited] {
    bool all = true;
    for (auto &a : awaited) {
      a.matched = a.port->matched(a.connection).value_or(0);
      all = all && a.matched >= a.peers;
    }
    return all;
  };
  // Discovery runs on Cyclone's threads; polling the matched counts costs nothing measurable
  // and keeps the readers' status masks (the receive loop's) untouched.
  auto pause = std::chrono::microseconds(50);
  bool complete = all_matched();
  while (!complete && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(pause);
    pause = std::min(pause * 2, std::chrono::microseconds(2000));
    complete = all_matched();
  }
  Json connections = Json::array();
  for (const auto &a : awaited)
    connections.push_back({{"port", a.port->name()},
                           {"connection", a.connection},
                           {"peers", a.peers},
                           {"matched", a.matched}});
  return Json{{"complete", complete}, {"connections", std::move(connections)}};
}

CallResult<Json> Host::op_release(const Json &, const control::RequestContext &) {
  shutdown("component.release");
  return Json::object();
}

void Host::shutdown(std::string_view why) {
  {
    std::lock_guard lock(lifecycle_);
    if (c().state() == State::Released)
      return;
    log().info("releasing ({})", why);
    // First, so that a call through them under way makes no further ones: the components it
    // would call are likely being released too.
    for (const auto &port : c().resource_ports_)
      port->disconnect_all();
    if (c().state() == State::Started) {
      stop_component();
      auto properties = c().lock_properties();
      if (auto ok = c().stop(); !ok)
        log().error("stop failed: {}", ok.error().message);
    }
    {
      auto properties = c().lock_properties();
      if (auto ok = c().release(); !ok)
        log().error("release failed: {}", ok.error().message);
    }
    for (const auto &port : c().ports_)
      port->disconnect_all();
    set_state(State::Released);
  }
  if (on_released_)
    on_released_();
}

} // namespace rsca::component::detail
