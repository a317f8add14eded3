#include "component/host.hpp"

#include <algorithm>
#include <tuple>

#include <fmt/format.h>
#include <pthread.h>
#include <sched.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstring>

#include "control/operation.hpp"
#include "profile/code_description.hpp"
#include "protocol/addresses.hpp"
#include "protocol/domain_ops.hpp"
#include "shm/process_arena.hpp"

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

} // namespace

profile::CodeDescription Host::describe(const Component &component) {
  profile::CodeDescription out;
  for (const auto &port : component.ports_)
    out.ports.push_back({port->name(), port->direction(), false});
  for (const auto &port : component.resource_ports_)
    out.ports.push_back({port->name(), profile::PortDirection::Uses, true});
  out.properties = component.properties_.bound_ids();
  return out;
}

// The ports' names against the SCD are checked as `rsca validate` checks them
// (profile::code_misfits); what only the live ports tell (their types, a name given twice) here.
Expected<void> Host::check_ports() const {
  const auto &scd = softpkg_->scd;
  Error error;
  auto fail = [&](std::string message) {
    error.add({{softpkg_->spd_path.string(), 0, 0}, "binding", std::move(message)});
  };
  profile::CodeDescription ports = describe(c());
  ports.properties.clear(); // checked as the PRF is loaded (PropertySet::load)
  for (auto &misfit : profile::code_misfits(ports, scd.get(), {}))
    fail(std::move(misfit));
  for (const auto &port : c().ports_) {
    if (find_port(port->name()) != port.get())
      fail(fmt::format("the component declares port \"{}\" twice", port->name()));
    const auto *definition = scd ? scd->find_port(port->name(), port->direction()) : nullptr;
    if (definition == nullptr)
      continue;
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
    if (definition != nullptr && !profile::is_control_interface(definition->repid))
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

Expected<void> Host::open(std::shared_ptr<ParticipantSource> participants,
                          std::shared_ptr<control::Server> endpoint,
                          std::function<void()> on_released, control::EndpointOptions options) {
  participants_ = std::move(participants);
  on_released_ = std::move(on_released);
  address_ = c().context().control_address;
  // The property lock is the one a callback may take (component.hpp): a callback delivered on a
  // DDS listener's thread runs only while it is free, so that it never waits there for it.
  auto loop = ReceiveLoop::start([this] { poll_ports(); }, &c().properties_mutex_);
  if (!loop)
    return tl::unexpected(loop.error());
  loop_ = std::move(*loop);
  configure_thread(loop_->thread(), "rx:");
  if (!endpoint) {
    auto participant = participants_->get();
    if (!participant)
      return tl::unexpected(participant.error());
    auto own = control::Endpoint::open(*participant, address_, std::move(options));
    if (!own)
      return tl::unexpected(own.error());
    endpoint = std::move(*own);
  }
  endpoint_ = std::move(endpoint);
  // A process with its host's arena connects to its host's processes through shared memory: it
  // joins DDS early only when the domain said a connection of it will go on DDS, else at the
  // first such connection, if any comes.
  if (!c().ports_.empty() && (shm::ProcessArena::inherited() == nullptr || c().context().joins_dds))
    participants_->join_in_background();
  serve_operations();
  // The domain calls next (initialize): the way back to it is made before it asks.
  endpoint_->prepare_replies(domain_address());
  std::lock_guard lock(lifecycle_);
  return endpoint_->announce(address_, "component", protocol::encode(announcement()));
}

void Host::close() {
  if (endpoint_) {
    endpoint_->withdraw(address_);
    endpoint_->stop_serving(address_); // waits for running handlers
  }
  stop_service();
  if (loop_) {
    loop_->stop();
    // No callback on a DDS listener's thread either (Delivery::Listener) from here on: the
    // component's own members go before its ports, which are what would stop the listeners.
    loop_->set_delivering(false);
    if (component_)
      for (const auto &port : c().ports_)
        port->quiesce();
  }
  // Only once the receive thread has stopped: it reports connection problems through the
  // endpoint (ThreadSanitizer saw it read endpoint_ while close cleared it, then call through
  // null: a consumer crashed as it exited).
  endpoint_.reset();
  component_.reset(); // its ports detach from the stopped loop
  loop_.reset();
  participants_.reset();
}

Expected<void> Host::bring_up(const Json &properties) {
  const std::string where = softpkg_->spd_path.string();
  const control::RequestContext context;
  if (auto ok = op_initialize({}, context); !ok)
    return make_error({where, 0, 0}, "initialize", ok.error().message);
  if (!properties.empty())
    if (auto ok = op_configure({properties}, context); !ok)
      return make_error({where, 0, 0}, "configure", ok.error().message);
  if (auto ok = op_start({}, context); !ok)
    return make_error({where, 0, 0}, "start", ok.error().message);
  return {};
}

std::vector<protocol::node::DevicePort> Host::ports() const {
  std::vector<protocol::node::DevicePort> ports;
  for (const auto &port : c().ports_) {
    const auto *definition =
        softpkg_->scd ? softpkg_->scd->find_port(port->name(), port->direction()) : nullptr;
    ports.push_back({port->name(), std::string(profile::to_string(port->direction())),
                     definition ? definition->repid : std::string(port::repid_of(port->type()))});
  }
  return ports;
}

protocol::component::Announcement Host::announcement() const {
  return {c().identifier(),
          c().name(),
          c().context().application,
          ::getpid(),
          std::string(to_string(c().state())),
          ports(),
          std::nullopt};
}

// Called with lifecycle_ held.
void Host::set_state(State state) {
  c().state_ = state;
  log().info("{}", to_string(state));
  if (state == State::Released || !endpoint_)
    return;
  if (auto ok = endpoint_->announce(address_, "component", protocol::encode(announcement())); !ok)
    log().warn("updating the announcement failed: {}", ok.error().to_string());
}

PortBase *Host::find_port(const std::string &name) const {
  for (const auto &port : c().ports_)
    if (port->name() == name)
      return port.get();
  return nullptr;
}

ResourceUsesPort *Host::find_resource_port(const std::string &name) const {
  for (const auto &port : c().resource_ports_)
    if (port->name() == name)
      return port.get();
  return nullptr;
}

void Host::poll_ports() {
  const bool deliver = loop_->delivering();
  for (const auto &port : c().ports_)
    if (port->direction() == profile::PortDirection::Provides)
      port->take_all(deliver);
  // Problems are looked for every kProblemCheck at most, not at every sample (ports.cpp says why).
  // A stopped application's writers stop too: the gaps of a stop are no problem. What is counted
  // while stopped, and the gap a start ends, is taken and dropped, at once on a start.
  const bool resumed = deliver && !delivered_at_last_poll_;
  delivered_at_last_poll_ = deliver;
  const auto now = std::chrono::steady_clock::now();
  if (!resumed && now - last_problem_check_ < kProblemCheck)
    return;
  last_problem_check_ = now;
  std::vector<ConnectionProblem> problems;
  for (const auto &port : c().ports_)
    for (auto &p : port->take_problems())
      if (deliver && !resumed)
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
  return protocol::domain_address(domain.empty() ? std::string_view("rsca") : domain);
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
    control::send<protocol::domain::ConnectionProblem>(
        *endpoint_, domain_address(),
        {c().context().application, c().context().name, key.first, key.second, count},
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

// Called with lifecycle_ held, when started: the service thread and port callbacks stop before
// the stop hook runs.
void Host::stop_component() {
  stop_service();
  if (loop_)
    loop_->set_delivering(false);
  for (const auto &port : c().ports_)
    port->quiesce();
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
