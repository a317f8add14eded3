#include "node/device_manager.hpp"

#include "allocator/device.hpp"

#include <atomic>
#include <mutex>
#include <set>
#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/host_name.hpp"
#include "common/install_layout.hpp"
#include "common/names.hpp"
#include "common/periodic.hpp"
#include "control/name_holder.hpp"
#include "control/operation.hpp"
#include "node/daemon_log.hpp"
#include "node/device_libraries.hpp"
#include "node/process_logs.hpp"
#include "process/proc_figures.hpp"
#include "profile/property_binding.hpp"
#include "profile/property_json.hpp"
#include "protocol/addresses.hpp"
#include "protocol/file_ops.hpp"

namespace rsca::node {
namespace {

using control::Status;
namespace op = protocol::node;

// What an execute leaves for the spawn and the reply's way back: a process started later than
// this before the caller's budget ends would likely be answered to nobody.
constexpr std::chrono::milliseconds kStartAllowance{50};

// Refuses an execute whose caller has stopped waiting (its budget_ms, counted from the request's
// arrival), or soon will: the caller has rolled its launch back, and the process would belong to
// nobody. `before`: what would have come next, for the message.
std::optional<control::CallError> budget_spent(const op::ExecuteRequest &request,
                                               const control::RequestContext &context,
                                               std::string_view before) {
  if (!request.budget_ms)
    return std::nullopt;
  const auto spent = std::chrono::duration_cast<std::chrono::milliseconds>(
      std::chrono::steady_clock::now() - context.received);
  if (spent + kStartAllowance <= std::chrono::milliseconds(*request.budget_ms))
    return std::nullopt;
  spdlog::warn("{}/{} not started: its caller's {} ms ran out before {} ({} ms spent)",
               request.application, request.component, *request.budget_ms, before, spent.count());
  return control::CallError{Status::Timeout, fmt::format("the caller's {} ms ran out before {}",
                                                         *request.budget_ms, before)};
}

// Why the node refuses an execute before it fetches anything, if it does. The control plane is
// not authenticated: any peer may send one. The application and component become the log's
// path (LOG_DIR/APPLICATION/COMPONENT.log): each must be a name. And the process runs from a
// package the domain delivered (the device runs only its executables): without one there is
// nothing the node may run.
std::optional<control::CallError> refusal(const op::ExecuteRequest &request) {
  for (const auto &[what, name] : {std::pair{"the application", &request.application},
                                   std::pair{"the component", &request.component}})
    if (auto ok = check_name(what, *name); !ok)
      return control::CallError{Status::BadRequest, ok.error().diagnostics().front().message};
  if (!request.package)
    return control::CallError{
        Status::BadRequest,
        fmt::format("{}/{}: a process without a package: a node runs only code its domain "
                    "delivered",
                    request.application, request.component)};
  return std::nullopt;
}

// The DCD's property values for one device, keyed by property id and by name.
Json overrides_of(const profile::ComponentInstantiation &ci, const profile::ResolvedSoftPkg &pkg) {
  Json out = Json::object();
  for (const auto &ref : ci.properties) {
    const auto *definition = pkg.find_property(profile::refid_of(ref));
    if (definition == nullptr)
      continue;
    auto value = profile::bind_property(*definition, ref);
    if (!value)
      continue; // the loader already refused invalid values
    out[profile::common_of(*definition).id] = profile::to_json(*value);
    out[profile::common_of(*definition).label()] = profile::to_json(*value);
  }
  return out;
}

// How often the logs' sizes are looked at: a process logging fast overshoots its bound by at most
// what it logs in this time.
constexpr std::chrono::seconds kLogRotationPeriod{1};
// Old logs are looked for once a minute: they are kept for hours at least.
constexpr std::chrono::seconds kLogSweepPeriod{60};

op::ProcessFigures figures_of(pid_t pid, const process::Figures &f) {
  return {pid, f.cpu_percent, f.rss_bytes, f.threads};
}

// `text` cut to what the announcement's contract takes (protocol/node_ops.hpp, FailedDevice): a
// field over its bound would have the domain refuse the whole announcement. excerpt() may write
// each byte as 4 and adds its length: a quarter, less that, fits.
std::string bounded(const std::string &text, std::size_t max) {
  return text.size() <= max ? text : excerpt(text, max / 4 - 32);
}

} // namespace

struct DeviceManager::Impl {
  // A member, not in the anonymous namespace: a field of that type in Impl (external linkage) is
  // an error (-Wsubobject-linkage) once this file is not the main file, in a unity build.
  struct RunningDevice {
    std::string id;
    std::string label;
    std::string softpkg;
    std::unique_ptr<LogicalDevice> device;
    // For the allocator: the PRF's allocation properties and the DCD's deployerrequires.
    Json allocation;
    Json deployer_requires;
    ExecutableDevice *executable() const { return dynamic_cast<ExecutableDevice *>(device.get()); }
  };

  NodeOptions options;
  std::shared_ptr<dds::Participant> participant;
  std::unique_ptr<control::Endpoint> endpoint;
  std::unique_ptr<HostData> host_data; // outlives the links, which use it
  std::unique_ptr<ProcessLinks> links; // relays through the endpoint
  std::unique_ptr<PackageCache> cache; // fetches through the endpoint
  std::shared_ptr<const profile::DeviceConfiguration> dcd;
  profile::ResolvedNode node;
  // The devices' implementations, from the libraries their SPDs name: before the devices, which
  // their code made, so that the devices go first.
  DeviceRegistry registry;
  DeviceLibraries libraries{{}};
  std::vector<RunningDevice> devices;
  std::vector<op::FailedDevice> failed; // the DCD's devices not started, announced with the rest
  std::atomic<bool> stopping{false};
  std::mutex endpoint_mutex;        // the endpoint's end against a process exit reported meanwhile
  process::CpuSampler sampler;      // node.top's: its last reading of each process
  std::optional<Periodic> rotation; // of its processes' logs, by size
  std::optional<Periodic> sweep;    // of the logs no process writes, by age

  Expected<void> start_devices();
  void not_started(op::FailedDevice failure);
  op::NodeAnnouncement announcement() const;
  void serve();
  ExecutableDevice *executable_device(const std::string &id) const;
  void report_exit(const protocol::domain::ComponentExitedReport &report);
  CallResult<op::ExecuteReply> execute(const op::ExecuteRequest &request,
                                       const control::RequestContext &context) const;
  Expected<void> open_cache();
  CallResult<op::TerminateReply> terminate(const op::TerminateRequest &request) const;
  op::StatusReply status() const;
  std::vector<op::ProcessRecord> running() const;
  CallResult<op::TopReply> top();
  CallResult<op::TapReply> tap(const op::TapRequest &request);
  void rotate_logs() const;
  void sweep_logs() const;
};

namespace {

// Why this daemon must not serve node `name`: a live node of another run already does
// (control/name_holder.hpp), a namesake from a copied DCD. Its own announcement would overwrite
// the holder's, and its stop would withdraw it: the domain took the holder for stopped while its
// processes ran on. A holder whose process is gone from this host is this node's last run (killed
// and restarted within its lease): that one is taken over, as ever.
std::optional<std::string> held_by_another(const dds::Participant &participant,
                                           const std::string &domain, const std::string &name,
                                           const std::filesystem::path &dcd) {
  spdlog::info("looking for another daemon of node {} (up to {} ms)", name,
               control::kNameCheck.count());
  auto held = control::live_holder<op::NodeAnnouncement>(
      participant, protocol::node_address(domain, name), fmt::format("node {}", name),
      control::own_program());
  if (!held)
    return std::nullopt;
  return fmt::format("{}: this node daemon (pid {} on host {}, DCD {}) does not start beside it; "
                     "give it another name in its DCD, or stop that one first",
                     *held, ::getpid(), host_name(), dcd.string());
}

// The DCD's device instances in the order they start: those with a start order by it (REDHAWK
// 2.2's componentinstantiation/@startorder), then the others in the DCD's order.
std::vector<
    std::pair<const profile::ResolvedDevicePlacement *, const profile::ComponentInstantiation *>>
start_order_of(const profile::ResolvedNode &node) {
  std::vector<
      std::pair<const profile::ResolvedDevicePlacement *, const profile::ComponentInstantiation *>>
      out;
  for (const auto &placed : node.devices)
    if (placed.softpkg)
      for (const auto &ci : placed.placement->instantiations)
        out.emplace_back(&placed, &ci);
  std::stable_sort(out.begin(), out.end(), [](const auto &a, const auto &b) {
    return a.second->start_order.value_or(UINT32_MAX) < b.second->start_order.value_or(UINT32_MAX);
  });
  return out;
}

// REDHAWK's loggingconfig of a device instance sets its log level; rsca's devices run inside the
// node daemon, whose log they write to: the node logs at least as verbosely as any of them asks.
void apply_logging_config(const profile::ResolvedNode &node) {
  for (const auto &placed : node.devices)
    for (const auto &ci : placed.placement->instantiations) {
      if (!ci.logging || !ci.logging->debug_level)
        continue;
      constexpr spdlog::level::level_enum kLevels[] = {
          spdlog::level::critical, spdlog::level::err,   spdlog::level::warn,
          spdlog::level::info,     spdlog::level::debug, spdlog::level::trace};
      const auto level = kLevels[std::clamp(*ci.logging->debug_level, 0, 5)];
      if (level < spdlog::get_level()) {
        spdlog::set_level(level);
        spdlog::info("logging at {}: the DCD's loggingconfig of {} asks for it",
                     spdlog::level::to_string_view(level), ci.id);
      }
    }
}

} // namespace

// A device that cannot be started as its profiles say (a file missing, its library not loaded)
// is left out with the reason, and the node starts with the others: it loses nothing it could run.
Expected<void> DeviceManager::Impl::start_devices() {
  for (const auto &[placed_ptr, ci_ptr] : start_order_of(node)) {
    const auto &placed = *placed_ptr;
    const auto &ci = *ci_ptr;
    const std::string label = ci.usage_name.empty() ? ci.id : ci.usage_name;
    const std::string id = fmt::format("{}:{}", dcd->name, label);
    if (!placed.softpkg->unavailable.empty()) {
      not_started({id, label, placed.softpkg->spd->name, "", "",
                   to_string(placed.softpkg->unavailable.front())});
      continue;
    }
    auto factory = libraries.factory_of(*placed.softpkg, registry);
    if (!factory) {
      auto &why = factory.error();
      not_started({id, label, placed.softpkg->spd->name, std::move(why.file), std::move(why.symbol),
                   std::move(why.reason)});
      continue;
    }
    DeviceContext context{id,
                          label,
                          dcd->name,
                          options.domain_name,
                          placed.softpkg,
                          &ci,
                          overrides_of(ci, *placed.softpkg),
                          participant,
                          options.exec_path,
                          options.log_dir,
                          participant->settings(),
                          [this](const auto &report) { report_exit(report); },
                          links.get(),
                          host_data.get()};
    auto device = (**factory)(context);
    if (!device)
      return tl::unexpected(device.error());
    spdlog::info("device {} ({}) started", id, placed.softpkg->spd->name);
    Json offers = Json::object();
    for (const auto &ref : ci.device_requires)
      if (const auto *simple = std::get_if<profile::SimpleRef>(&ref))
        offers[simple->refid] = simple->value;
    devices.push_back({id, label, placed.softpkg->spd->name, std::move(*device),
                       allocator::allocation_properties_json(*placed.softpkg), offers});
  }
  return {};
}

void DeviceManager::Impl::not_started(op::FailedDevice failure) {
  spdlog::warn("device {} ({}) not started: {}", failure.id, failure.softpkg, failure.reason);
  if (failed.size() >= op::NodeAnnouncement::kMaxFailedDevices)
    return; // the log has them all
  using F = op::FailedDevice;
  failed.push_back({bounded(failure.id, 2 * F::kMaxName), bounded(failure.label, F::kMaxName),
                    bounded(failure.softpkg, F::kMaxName), bounded(failure.file, F::kMaxPath),
                    bounded(failure.symbol, F::kMaxName), bounded(failure.reason, F::kMaxReason)});
}

op::NodeAnnouncement DeviceManager::Impl::announcement() const {
  op::NodeAnnouncement out{dcd->name, static_cast<std::int64_t>(getpid()), host_name(), {}, true,
                           {}};
  if (!failed.empty())
    out.failed_devices = failed;
  for (const auto &d : devices) {
    op::DeviceRecord record{d.id,
                            d.label,
                            d.softpkg,
                            d.device->kind(),
                            d.device->properties(),
                            d.device->capacity(),
                            d.allocation,
                            d.deployer_requires,
                            d.device->address(),
                            {}};
    if (!record.address.empty())
      record.ports = d.device->ports();
    out.devices.push_back(std::move(record));
  }
  return out;
}

ExecutableDevice *DeviceManager::Impl::executable_device(const std::string &id) const {
  for (const auto &d : devices)
    if ((id.empty() || d.id == id) && d.executable() != nullptr)
      return d.executable();
  return nullptr;
}

void DeviceManager::Impl::report_exit(const protocol::domain::ComponentExitedReport &report) {
  std::lock_guard lock(endpoint_mutex); // the reaper's thread: the endpoint may be going
  if (stopping.load() || !endpoint)
    return;
  spdlog::warn("process {} ({}/{}) exited on its own: {}", report.pid, report.application,
               report.component, report.status);
  // Fire and forget: the reply is not needed, and the reaper that calls this must not block.
  control::send<protocol::domain::ComponentExited>(
      *endpoint, protocol::domain_address(options.domain_name), report, std::chrono::seconds(2));
}

CallResult<op::ExecuteReply>
DeviceManager::Impl::execute(const op::ExecuteRequest &request,
                             const control::RequestContext &context) const {
  ExecutableDevice *device = executable_device(request.device);
  if (device == nullptr)
    return control::call_error(Status::NotFound, fmt::format("node {} has no executable device {}",
                                                             dcd->name, request.device));
  if (request.launch && request.launch->size() > protocol::file::kMaxLaunchLength)
    return control::call_error(Status::BadRequest, "launch: an id too long");
  if (auto refused = refusal(request)) {
    spdlog::warn("node.execute refused: {}", excerpt(refused->message, 4 * kExcerptLength));
    return tl::unexpected(*refused);
  }
  if (auto spent = budget_spent(request, context, "the node took it up"))
    return tl::unexpected(*spent);
  auto package = cache->acquire(*request.package, request.launch.value_or(""));
  if (!package) {
    spdlog::warn("{}/{} not started: its package: {}", request.application, request.component,
                 package.error().message);
    return control::call_error(package.error().status,
                               fmt::format("node {}: {}", dcd->name, package.error().message));
  }
  if (auto spent = budget_spent(request, context, "its package was delivered"))
    return tl::unexpected(*spent);
  return device->execute(request, std::move(*package));
}

Expected<void> DeviceManager::Impl::open_cache() {
  CacheOptions cache_options = options.cache;
  if (cache_options.dir.empty())
    cache_options.dir = (options.log_dir / ".." / "cache" / dcd->name).lexically_normal();
  const auto domain = protocol::domain_address(options.domain_name);
  auto opened = PackageCache::open(
      cache_options,
      [this, domain, timeout = cache_options.piece_timeout](const protocol::file::ReadRequest &r) {
        return endpoint->call(domain, std::string(protocol::file::Read::name), protocol::encode(r),
                              timeout);
      });
  if (!opened)
    return tl::unexpected(opened.error());
  cache = std::move(*opened);
  return {};
}

CallResult<op::TerminateReply>
DeviceManager::Impl::terminate(const op::TerminateRequest &request) const {
  for (const auto &d : devices) {
    if (d.executable() == nullptr)
      continue;
    auto result = d.executable()->terminate(request);
    if (result || result.error().status != Status::NotFound)
      return result;
  }
  return control::call_error(
      Status::NotFound, fmt::format("node {} did not start process {}", dcd->name, request.pid));
}

std::vector<op::ProcessRecord> DeviceManager::Impl::running() const {
  std::vector<op::ProcessRecord> out;
  for (const auto &d : devices)
    if (d.executable() != nullptr)
      for (auto &p : d.executable()->processes())
        out.push_back(std::move(p));
  return out;
}

op::StatusReply DeviceManager::Impl::status() const {
  auto a = announcement();
  op::StatusReply status{
      std::move(a.node), a.pid, std::move(a.host), std::move(a.devices), running(), {}, {}};
  if (host_data) {
    const auto held = host_data->counts();
    status.shared_memory =
        op::SharedMemoryStatus{held.rings, held.ends, held.pages, held.bytes_in_use, held.relays};
  }
  const auto cached = cache->counts();
  status.cache =
      op::PackageCacheStatus{cached.packages, cached.bytes,         options.cache.max_bytes,
                             cached.fetched,  cached.fetched_bytes, cached.reused};
  return status;
}

// The node daemon's figures and those of each process its devices run; a process that exited
// meanwhile is left out.
CallResult<op::TopReply> DeviceManager::Impl::top() {
  const auto self = ::getpid();
  auto own = sampler.read(self);
  if (!own)
    return control::call_error(Status::Failed, "cannot read the node's own /proc figures");
  op::TopReply reply{dcd->name, host_name(), figures_of(self, *own), {}};
  std::set<pid_t> alive{self};
  for (const auto &p : running()) {
    const auto pid = static_cast<pid_t>(p.pid);
    auto figures = sampler.read(pid);
    if (!figures || reply.processes.size() >= op::TopReply::kMaxProcesses)
      continue;
    alive.insert(pid);
    auto [application, component] = op::split_process_label(p.label);
    reply.processes.push_back(
        {std::move(application), std::move(component), figures_of(pid, *figures)});
  }
  sampler.keep_only(alive);
  return reply;
}

// A viewer's tap of a same-host topic (rsca echo, rsca hz), opened or renewed.
CallResult<op::TapReply> DeviceManager::Impl::tap(const op::TapRequest &request) {
  if (!host_data)
    return control::call_error(Status::Unavailable,
                               "this node has no shared memory: its topics go over DDS");
  auto tapped = host_data->tap(
      {request.topic, 0, request.repid, std::chrono::milliseconds(request.lease_ms)});
  if (!tapped)
    return control::call_error(Status::NotFound, tapped.error());
  return op::TapReply{std::move(*tapped)};
}

void DeviceManager::Impl::rotate_logs() const {
  for (const auto &p : running())
    if (auto rotated = rotate_if_over(p.log, options.log_max_bytes); !rotated)
      spdlog::warn("{}: {}", p.label, rotated.error().to_string());
    else if (*rotated)
      spdlog::debug("{}: log rotated", p.label);
}

void DeviceManager::Impl::sweep_logs() const {
  const auto keep = std::chrono::duration_cast<std::chrono::seconds>(options.log_keep);
  if (const auto deleted = node::sweep_logs(options.log_dir, running(), keep); deleted > 0)
    spdlog::info("{} logs no process wrote for {} h deleted", deleted, options.log_keep.count());
}

void DeviceManager::Impl::serve() {
  control::serve<op::Execute>(*endpoint, [this](const auto &request, const auto &context) {
    return execute(request, context);
  });
  control::serve<op::Terminate>(
      *endpoint, [this](const auto &request, const auto &) { return terminate(request); });
  control::serve<op::Status>(*endpoint, [this](const auto &, const auto &) {
    return CallResult<op::StatusReply>(status());
  });
  control::serve<op::Top>(*endpoint, [this](const auto &, const auto &) { return top(); });
  control::serve<op::Logs>(*endpoint, [this](const auto &request, const auto &) {
    return read_log(options.log_dir, request, running());
  });
  control::serve<op::DaemonLogs>(*endpoint, [this](const auto &request, const auto &) {
    return read_daemon_log(options.log_dir, dcd->name, request);
  });
  control::serve<op::Tap>(*endpoint,
                          [this](const auto &request, const auto &) { return tap(request); });
}

DeviceManager::DeviceManager(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

DeviceManager::~DeviceManager() {
  impl_->rotation.reset(); // it reads the devices' processes
  impl_->sweep.reset();
  impl_->stopping = true;
  impl_->endpoint->withdraw();
  impl_->links->close(); // relays under way fail: the endpoint's handlers return
  // The endpoint goes first: closing it waits for the handlers still running, which use the
  // devices (a node.terminate still escalating while the devices went was a double free).
  // Handlers under way (an execute fetching its package) call through impl_->endpoint, which
  // reset() clears before the endpoint's destructor waits for them: UBSan saw a package fetch
  // call through null as a node stopped. They are waited for here, the pointer still set.
  impl_->endpoint->stop_serving();
  {
    std::lock_guard lock(impl_->endpoint_mutex);
    impl_->endpoint.reset();
  }
  impl_->devices.clear(); // terminates whatever the GPP still runs
  impl_->links.reset();
}

const std::string &DeviceManager::node_name() const {
  return impl_->dcd->name;
}

Expected<std::unique_ptr<DeviceManager>>
DeviceManager::create(std::shared_ptr<dds::Participant> participant, NodeOptions options) {
  auto impl = std::make_unique<Impl>();
  impl->options = std::move(options);
  if (impl->options.library_path.empty())
    impl->options.library_path = layout::library_folders();
  impl->libraries = DeviceLibraries(impl->options.library_path);
  impl->participant = participant;
  profile::ProfileLoader loader(impl->options.sdrroot);
  auto node = loader.load_node(impl->options.dcd);
  if (!node)
    return tl::unexpected(node.error());
  impl->node = std::move(*node);
  impl->dcd = impl->node.dcd;
  for (const auto &w : impl->node.tolerated)
    spdlog::warn("{}", to_string(w));
  apply_logging_config(impl->node);
  // Before anything of the node exists: a namesake refused leaves the holder's host as it was.
  if (auto held = held_by_another(*participant, impl->options.domain_name, impl->dcd->name,
                                  impl->options.dcd))
    return make_error({impl->options.dcd.string(), 0, 0}, "name-taken", *held);
  control::EndpointOptions endpoint_options;
  endpoint_options.hold_requests = true; // until its devices run and their handlers are there
  auto endpoint = control::Endpoint::open(
      participant, protocol::node_address(impl->options.domain_name, impl->dcd->name),
      std::move(endpoint_options));
  if (!endpoint)
    return tl::unexpected(endpoint.error());
  impl->endpoint = std::move(*endpoint);
  if (auto why = shm::check(impl->options.rings))
    return make_error({impl->options.dcd.string(), 0, 0}, "ring", *why);
  // Without shared memory the node still works: its processes then connect over DDS.
  if (auto data = HostData::create(impl->options.rings); data)
    impl->host_data = std::move(*data);
  else
    spdlog::warn("no shared memory for this host's data ({}): same-host connections use DDS",
                 data.error().to_string());
  if (impl->host_data) {
    auto relayed = impl->host_data->start_relay(
        [participant](const shm::Arena &arena,
                      std::uint64_t doorbell) -> Expected<std::unique_ptr<TopicRelay>> {
          auto bridge = TopicBridge::start(participant, arena, doorbell);
          if (!bridge)
            return tl::unexpected(bridge.error());
          return std::unique_ptr<TopicRelay>(std::move(*bridge));
        });
    if (!relayed)
      return tl::unexpected(relayed.error());
    auto tapped = impl->host_data->start_taps(
        [participant](const shm::Arena &arena,
                      std::uint64_t doorbell) -> Expected<std::unique_ptr<TopicTaps>> {
          return TopicTaps::start(participant, arena, doorbell);
        });
    if (!tapped)
      return tl::unexpected(tapped.error());
  }
  auto links = ProcessLinks::start(*impl->endpoint, impl->host_data.get());
  if (!links)
    return tl::unexpected(links.error());
  impl->links = std::move(*links);
  // Before anything serves or is announced: a node that cannot listen where it is told stops
  // with nothing to take down but its links.
  if (impl->options.control_socket)
    if (auto ok = impl->links->listen(impl->options.control_socket->string()); !ok)
      return tl::unexpected(ok.error());
  if (auto ok = impl->open_cache(); !ok)
    return tl::unexpected(ok.error());
  if (auto ok = impl->start_devices(); !ok)
    return tl::unexpected(ok.error());
  if (impl->options.log_max_bytes > 0)
    impl->rotation.emplace(kLogRotationPeriod, [raw = impl.get()] { raw->rotate_logs(); });
  impl->sweep.emplace(kLogSweepPeriod, [raw = impl.get()] { raw->sweep_logs(); });
  impl->serve();
  impl->endpoint->start_serving();
  // The domain is the node's caller, and the node calls it: both ways are made now, so the
  // first launch does not wait for DDS to match them.
  impl->endpoint->prepare(protocol::domain_address(impl->options.domain_name));
  impl->endpoint->prepare_replies(protocol::domain_address(impl->options.domain_name));
  if (auto ok = impl->endpoint->announce("node", protocol::encode(impl->announcement())); !ok)
    return tl::unexpected(ok.error());
  spdlog::info("node {} announced with {} device(s)", impl->dcd->name, impl->devices.size());
  return std::unique_ptr<DeviceManager>(new DeviceManager(std::move(impl)));
}

} // namespace rsca::node
