#include "gpp_device.hpp"

#include <unistd.h>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <spdlog/spdlog.h>

#include "affinity.hpp"
#include "common/exec_environment.hpp"
#include "common/names.hpp"
#include "control/link_socket.hpp"
#include "host_info.hpp"
#include "node/process_logs.hpp"
#include "protocol/exec_params.hpp"
#include "run_as.hpp"
#include "shm/arena.hpp"

namespace rsca::gpp {

using control::Status;
using node::CallResult;
using node::Json;

namespace {

bool is_executable(const std::filesystem::path &p) {
  std::error_code ec;
  return std::filesystem::is_regular_file(p, ec) && ::access(p.c_str(), X_OK) == 0;
}

// A DCD value for `name`, if the DCD gives one.
std::optional<Json> override_of(const node::DeviceContext &context, const char *name) {
  if (context.overrides.contains(name))
    return context.overrides.at(name);
  return std::nullopt;
}

} // namespace

GppDevice::GppDevice(node::DeviceContext context, std::optional<process::Credentials> run_as)
    : context_(std::move(context)), run_as_(std::move(run_as)),
      launcher_([this](ProcessId pid, ExitStatus status) { on_exit(pid, status); },
                [this](const ExecRequest &request) { return start_process(request); }) {
  const HostInfo host = read_host_info();
  properties_ = {
      {"os_name", override_of(context_, "os_name").value_or(host.os_name)},
      {"processor_name", override_of(context_, "processor_name").value_or(host.processor_name)},
      {"hostname", host.hostname},
      {"scheduling_policy",
       override_of(context_, "scheduling_policy").value_or(Json("fixed-priority"))},
      {"pin_admitted_cpu", override_of(context_, "pin_admitted_cpu").value_or(Json(true))},
      {"fork_server", override_of(context_, "fork_server").value_or(Json(true))}};
  capacity_ = {{"cpu_capacity",
                override_of(context_, "cpu_capacity").value_or(Json(host.cpu_cores * 100.0))},
               {"mem_capacity", override_of(context_, "mem_capacity")
                                    .value_or(Json(static_cast<double>(host.memory_total_bytes) /
                                                   (1024.0 * 1024.0)))}};
}

namespace {

// A boolean property as a DCD may set it: true, or the text "true".
bool is_true(const Json &value) {
  return value.is_boolean() ? value.get<bool>()
                            : !(value.is_string() && value.get<std::string>() == "false");
}

} // namespace

bool GppDevice::pins_admitted_cpu() const {
  return is_true(properties_.at("pin_admitted_cpu"));
}

bool GppDevice::uses_fork_servers() const {
  return is_true(properties_.at("fork_server"));
}

Expected<process::Child> GppDevice::start_process(const ExecRequest &request) {
  if (uses_fork_servers())
    if (auto forked = fork_servers_.fork(request))
      return std::move(*forked);
  return process::spawn(request, process::Group::Own);
}

Expected<std::unique_ptr<node::LogicalDevice>>
GppDevice::create(const node::DeviceContext &context) {
  auto run_as = component_user(context);
  if (!run_as)
    return tl::unexpected(run_as.error());
  return std::unique_ptr<node::LogicalDevice>(
      std::make_unique<GppDevice>(context, std::move(*run_as)));
}

// rsca's component host in the node's own exec path, by its bare name.
std::optional<std::filesystem::path> GppDevice::component_host() const {
  for (const auto &dir : context_.exec_path)
    if (is_executable(dir / protocol::node::kComponentHostProgram))
      return dir / protocol::node::kComponentHostProgram;
  return std::nullopt;
}

// The program a request runs: the entry point beside its SPD inside its package (fetched from
// the domain by content hash and verified: node/package_cache.hpp), or, without an SPD, the
// component host. Nothing else: an absolute entry point (REDHAWK allows one) or one outside the
// package would let anyone who can send a request run any program of this host.
CallResult<std::filesystem::path>
GppDevice::packaged_executable(const protocol::node::ExecuteRequest &r,
                               const node::PackageLease &package) const {
  const auto refused = [&](const std::string &why) {
    return control::call_error(
        Status::BadRequest,
        fmt::format("{}: entry point \"{}\" {}", context_.id, excerpt(r.entrypoint), why));
  };
  const std::filesystem::path ep(r.entrypoint);
  if (ep.is_absolute())
    return refused("is absolute: a node runs only the programs of its package");
  if (r.spd_dir.empty()) {
    if (r.entrypoint != protocol::node::kComponentHostProgram)
      return refused(fmt::format("has no SPD: only {} runs without one",
                                 protocol::node::kComponentHostProgram));
    if (auto host = component_host())
      return *host;
    return control::call_error(Status::Failed,
                               fmt::format("{}: no {} in its exec path", context_.id,
                                           protocol::node::kComponentHostProgram));
  }
  const auto inside = (std::filesystem::path(r.spd_dir) / ep).lexically_normal();
  if (inside.is_absolute() || inside.empty() || *inside.begin() == "..")
    return control::call_error(
        Status::BadRequest,
        fmt::format("{}: entry point {} lies outside its package", context_.id, inside.string()));
  return package.root() / inside;
}

namespace {

// The process's LD_LIBRARY_PATH: its package's library folders (checked as the package's own
// folders when the package was taken), then the node's own path, which it would have inherited.
std::string library_path(const std::filesystem::path &root, const std::vector<std::string> &dirs) {
  std::vector<std::string> parts;
  for (const auto &dir : dirs)
    parts.push_back((root / dir).string());
  if (const char *inherited = std::getenv("LD_LIBRARY_PATH"); inherited && *inherited)
    parts.emplace_back(inherited);
  return fmt::format("{}", fmt::join(parts, ":"));
}

} // namespace

CallResult<protocol::node::ExecuteReply>
GppDevice::execute(const protocol::node::ExecuteRequest &r,
                   std::shared_ptr<const node::PackageLease> package) {
  const std::string &application = r.application;
  const std::string &component = r.component;
  // An affinity this host cannot honour refuses the process before it starts.
  std::optional<ProcessPlacement> placement;
  if (r.affinity) {
    auto resolved = resolve_affinity(*r.affinity);
    if (!resolved)
      return control::call_error(Status::BadRequest,
                                 fmt::format("{}: {}/{}: {}", context_.id, application, component,
                                             resolved.error().diagnostics().front().message));
    placement = std::move(*resolved);
  }
  if (!package) // the node refuses it first (node/device_manager.cpp)
    return control::call_error(Status::BadRequest, fmt::format("{}: {}/{}: no package", context_.id,
                                                               application, component));
  ExecRequest request;
  auto program = packaged_executable(r, *package);
  if (!program)
    return tl::unexpected(program.error());
  request.program = std::move(*program);
  request.working_dir = package->root();
  request.user = run_as_;
  request.args = r.args;
  request.env = context_.dds.component_environment();
  // The component dies with this node: it checks that its parent is still this process.
  request.env.emplace_back(kNodePidVariable, std::to_string(::getpid()));
  if (!pins_admitted_cpu())
    request.env.emplace_back(kPinAdmittedVariable, "0");
  if (r.package && !r.package->library_dirs.empty())
    request.env.emplace_back("LD_LIBRARY_PATH",
                             library_path(package->root(), r.package->library_dirs));
  request.log_file = context_.log_dir / application / (component + ".log");
  std::error_code no_log; // none yet: this process's lines begin at 0
  const std::uint64_t log_offset = std::filesystem::file_size(request.log_file, no_log);
  if (!no_log) { // written now: the node's sweep of old logs leaves it (node/process_logs.hpp)
    std::error_code untouched;
    std::filesystem::last_write_time(request.log_file,
                                     std::filesystem::file_time_type::clock::now(), untouched);
  }
  request.label = protocol::node::process_label(application, component);
  // The process's control goes through this node (node/process_links.hpp): it gets its end of
  // the link as a known descriptor.
  std::optional<std::pair<process::Fd, process::Fd>> link;
  if (context_.links != nullptr) {
    auto pair = control::make_link_pair();
    if (!pair)
      return control::call_error(Status::Failed, fmt::format("{}: {}", context_.id, pair.error()));
    link = std::move(*pair);
    request.inherit.push_back({link->second.get(), protocol::link::kNodeLinkFd});
    request.env.emplace_back(protocol::link::kNodeLinkVariable,
                             std::to_string(protocol::link::kNodeLinkFd));
  }
  // Its same-host connections go through the host's shared memory (node/host_data.hpp): it maps
  // the arena, and gets a page of it for its doorbells.
  std::optional<std::uint64_t> page;
  if (context_.host_data != nullptr && link) {
    if (auto reserved = context_.host_data->reserve_page()) {
      page = reserved->first;
      request.inherit.push_back({context_.host_data->arena_fd(), shm::kArenaFd});
      request.env.emplace_back(shm::kArenaVariable, reserved->second);
    }
  }
  // The process starts on its CPUs: it inherits the spawning thread's mask while it is set.
  const std::vector<unsigned> cpus = placement ? placement->cpus : std::vector<unsigned>{};
  auto pid = spawner_.run([&]() -> node::CallResult<ProcessId> {
    std::optional<ScopedThreadCpus> pinned;
    if (!cpus.empty() && !pinned.emplace(cpus).pinned())
      return control::call_error(Status::Failed,
                                 fmt::format("{}: cannot run on CPUs {}: {}", context_.id,
                                             fmt::join(cpus, ","), std::strerror(errno)));
    auto started = launcher_.execute(request);
    if (!started)
      return control::call_error(Status::Failed,
                                 fmt::format("{}: {}", context_.id, started.error().to_string()));
    return *started;
  });
  if (!pid) {
    if (page)
      context_.host_data->release_page(*page);
    return tl::unexpected(pid.error());
  }
  if (placement) {
    if (auto applied = apply_nice(*pid, *placement); !applied) {
      (void)launcher_.terminate(*pid, {});
      if (page)
        context_.host_data->release_page(*page);
      return control::call_error(Status::Failed,
                                 fmt::format("{}: {}", context_.id, applied.error().to_string()));
    }
    spdlog::info("{}/{} (pid {}) runs on CPUs {}{}", application, component, *pid,
                 placement->cpus.empty() ? "any"
                                         : fmt::format("{}", fmt::join(placement->cpus, ",")),
                 placement->nice ? fmt::format(", nice {}", *placement->nice) : "");
  }
  if (page)
    context_.host_data->adopt(*pid, *page);
  auto addresses = protocol::control_addresses(request.args);
  if (link) {
    link->second.reset(); // the child's end is the child's alone
    context_.links->attach(*pid, std::move(link->first), addresses);
  }
  {
    std::lock_guard lock(mutex_);
    protocol::domain::ComponentExitedReport owner;
    owner.application = application;
    owner.component = component;
    owner.addresses = std::move(addresses);
    owners_[*pid] = std::move(owner);
    packages_[*pid] = std::move(package);
    log_starts_[*pid] = no_log ? 0 : log_offset;
  }
  // A process that exited before it was recorded above found nothing to report or release: what
  // on_exit would have done is done now (whoever takes the records first does it, once).
  if (auto status = launcher_.wait_for_exit(*pid, std::chrono::milliseconds(0)))
    on_exit(*pid, *status);
  spdlog::info("{}: executed {} as pid {} (log {})", context_.id, request.program.string(), *pid,
               request.log_file.string());
  return protocol::node::ExecuteReply{*pid, request.log_file.string(), no_log ? 0 : log_offset};
}

CallResult<protocol::node::TerminateReply>
GppDevice::terminate(const protocol::node::TerminateRequest &r) {
  const auto pid = static_cast<ProcessId>(r.pid);
  if (pid != r.pid)
    return control::call_error(Status::BadRequest, fmt::format("no such pid {}", r.pid));
  {
    std::lock_guard lock(mutex_);
    if (owners_.count(pid) == 0)
      return control::call_error(Status::NotFound,
                                 fmt::format("{} did not start pid {}", context_.id, pid));
  }
  auto ok = launcher_.terminate(pid);
  if (!ok)
    return control::call_error(Status::Failed, ok.error().to_string());
  std::lock_guard lock(mutex_);
  owners_.erase(pid);
  packages_.erase(pid);
  log_starts_.erase(pid);
  return protocol::node::TerminateReply{pid};
}

std::vector<protocol::node::ProcessRecord> GppDevice::processes() const {
  std::vector<protocol::node::ProcessRecord> list;
  for (const auto &p : launcher_.list())
    if (p.running)
      list.push_back({p.pid, p.label, p.log_file.string()});
  return list;
}

void GppDevice::on_exit(ProcessId pid, const ExitStatus &status) {
  if (context_.links != nullptr)
    context_.links->detach(pid);
  std::shared_ptr<const node::PackageLease> package; // let go outside the lock
  std::uint64_t log_start = 0;
  {
    std::lock_guard lock(mutex_);
    if (auto it = packages_.find(pid); it != packages_.end()) {
      package = std::move(it->second);
      packages_.erase(it);
    }
    if (auto it = log_starts_.find(pid); it != log_starts_.end()) {
      log_start = it->second;
      log_starts_.erase(it);
    }
  }
  if (status.requested)
    return;
  protocol::domain::ComponentExitedReport report;
  {
    std::lock_guard lock(mutex_);
    auto it = owners_.find(pid);
    if (it == owners_.end())
      return;
    report = std::move(it->second);
    owners_.erase(it);
  }
  report.pid = pid;
  report.device = context_.id;
  report.status = describe(status);
  report.exit_code = status.exit_code;
  report.signal = status.signal;
  // Why a process exited is mostly in its last words: a launch that fails on it shows them (a few
  // KiB of a local file, read on the reaper's thread).
  using Report = protocol::domain::ComponentExitedReport;
  report.log_tail =
      node::log_tail(context_.log_dir / report.application / (report.component + ".log"), log_start,
                     Report::kMaxLogTailLines, Report::kMaxLogTailBytes);
  context_.report_exit(report);
}

void register_gpp(node::DeviceRegistry &registry) {
  registry.add("rsca.GPP", GppDevice::create);
  registry.add("GPP", GppDevice::create); // REDHAWK's name for the same device
}

} // namespace rsca::gpp
