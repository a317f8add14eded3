#include "gpp_device.hpp"

#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/exec_environment.hpp"
#include "host_info.hpp"

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

GppDevice::GppDevice(node::DeviceContext context)
    : context_(std::move(context)),
      launcher_([this](ProcessId pid, ExitStatus status) { on_exit(pid, status); }) {
  const HostInfo host = read_host_info();
  properties_ = {
      {"os_name", override_of(context_, "os_name").value_or(host.os_name)},
      {"processor_name", override_of(context_, "processor_name").value_or(host.processor_name)},
      {"hostname", host.hostname},
      {"scheduling_policy",
       override_of(context_, "scheduling_policy").value_or(Json("fixed-priority"))}};
  capacity_ = {{"cpu_capacity",
                override_of(context_, "cpu_capacity").value_or(Json(host.cpu_cores * 100.0))},
               {"mem_capacity", override_of(context_, "mem_capacity")
                                    .value_or(Json(static_cast<double>(host.memory_total_bytes) /
                                                   (1024.0 * 1024.0)))}};
}

Expected<std::unique_ptr<node::LogicalDevice>>
GppDevice::create(const node::DeviceContext &context) {
  return std::unique_ptr<node::LogicalDevice>(std::make_unique<GppDevice>(context));
}

// Where the entrypoint an SPD names is: an absolute path as is; a relative one beside the SPD;
// else the file of that name in the node's exec path (how a development build is found).
std::filesystem::path GppDevice::find_executable(const std::string &entrypoint,
                                                 const std::string &spd_dir) const {
  const std::filesystem::path ep(entrypoint);
  if (ep.is_absolute())
    return ep;
  if (!spd_dir.empty() && is_executable(std::filesystem::path(spd_dir) / ep))
    return std::filesystem::path(spd_dir) / ep;
  for (const auto &dir : context_.exec_path)
    if (is_executable(dir / ep.filename()))
      return dir / ep.filename();
  return std::filesystem::path(spd_dir) / ep;
}

namespace {

// Every component a process serves: one, or all those of a component host.
std::vector<std::string> control_addresses(const std::vector<std::string> &args) {
  std::vector<std::string> addresses;
  for (std::size_t i = 0; i + 1 < args.size(); i += 2)
    if (args[i] == "CONTROL_ADDRESS")
      addresses.push_back(args[i + 1]);
  return addresses;
}

} // namespace

CallResult<Json> GppDevice::execute(const Json &body) {
  const std::string application = body.value("application", "");
  const std::string component = body.value("component", "");
  ExecRequest request;
  request.executable = find_executable(body.value("entrypoint", ""), body.value("spd_dir", ""));
  request.args = body.value("args", std::vector<std::string>{});
  request.env = context_.dds.component_environment();
  // The component dies with this node: it checks that its parent is still this process.
  request.env.emplace_back(kNodePidVariable, std::to_string(::getpid()));
  request.log_file = context_.log_dir / application / (component + ".log");
  request.label = fmt::format("{}/{}", application, component);
  auto pid = launcher_.execute(request);
  if (!pid)
    return control::call_error(Status::Failed,
                               fmt::format("{}: {}", context_.id, pid.error().to_string()));
  {
    std::lock_guard lock(mutex_);
    owners_[*pid] = {{"application", application},
                     {"component", component},
                     {"addresses", control_addresses(request.args)}};
  }
  spdlog::info("{}: executed {} as pid {} (log {})", context_.id, request.executable.string(), *pid,
               request.log_file.string());
  return Json{{"pid", *pid}, {"log", request.log_file.string()}};
}

CallResult<Json> GppDevice::terminate(const Json &body) {
  const ProcessId pid = body.value("pid", 0);
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
  return Json{{"pid", pid}};
}

Json GppDevice::processes() const {
  Json list = Json::array();
  for (const auto &p : launcher_.list())
    if (p.running)
      list.push_back({{"pid", p.pid}, {"label", p.label}, {"log", p.log_file.string()}});
  return list;
}

void GppDevice::on_exit(ProcessId pid, const ExitStatus &status) {
  if (status.requested)
    return;
  Json report;
  {
    std::lock_guard lock(mutex_);
    auto it = owners_.find(pid);
    if (it == owners_.end())
      return;
    report = it->second;
    owners_.erase(it);
  }
  report["pid"] = pid;
  report["device"] = context_.id;
  report["status"] = describe(status);
  report["exit_code"] = status.exit_code;
  report["signal"] = status.signal;
  context_.report_exit(report);
}

void register_gpp(node::DeviceRegistry &registry) {
  registry.add("rsca.GPP", GppDevice::create);
  registry.add("GPP", GppDevice::create); // REDHAWK's name for the same device
}

} // namespace rsca::gpp
