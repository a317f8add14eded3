// The GPP: the ExecutableDevice of a host. Its matching properties (os_name, processor_name, as
// REDHAWK's GPP names them) and capacities (CPU and memory) come from the host itself, unless the
// DCD sets them; it executes component processes, each in its own process group with its own
// log file, as its run_as user (gpp/run_as.hpp), and terminates them with bounded escalation. It
// runs only an executable of a package the node took from its cache, or rsca's component host.
#pragma once

#include <memory>

#include "fork_servers.hpp"
#include "node/logical_device.hpp"
#include "process/credentials.hpp"
#include "process/spawn_thread.hpp"
#include "process_launcher.hpp"

namespace rsca::gpp {

class GppDevice final : public node::ExecutableDevice {
public:
  static Expected<std::unique_ptr<node::LogicalDevice>> create(const node::DeviceContext &context);

  std::string kind() const override { return "gpp"; }
  node::Json properties() const override { return properties_; }
  // Its pin_admitted_cpu property (GPP.prf.xml): periodic components pinned to their CPU.
  bool pins_admitted_cpu() const;
  // Its fork_server property (GPP.prf.xml): processes forked from fork servers of their
  // executables.
  bool uses_fork_servers() const;
  node::Json capacity() const override { return capacity_; }
  node::CallResult<protocol::node::ExecuteReply>
  execute(const protocol::node::ExecuteRequest &request,
          std::shared_ptr<const node::PackageLease> package) override;
  node::CallResult<protocol::node::TerminateReply>
  terminate(const protocol::node::TerminateRequest &request) override;
  std::vector<protocol::node::ProcessRecord> processes() const override;

  // `run_as`: whom its processes run as (gpp/run_as.hpp); none: as the node.
  GppDevice(node::DeviceContext context, std::optional<process::Credentials> run_as);

private:
  std::optional<std::filesystem::path> component_host() const;
  node::CallResult<std::filesystem::path>
  packaged_executable(const protocol::node::ExecuteRequest &request,
                      const node::PackageLease &package) const;
  void on_exit(ProcessId pid, const ExitStatus &status);
  // How the launcher starts a process: forked by a fork server when there is one, else spawned.
  Expected<process::Child> start_process(const ExecRequest &request);

  node::DeviceContext context_;
  node::Json properties_;
  node::Json capacity_;
  std::optional<process::Credentials> run_as_;
  std::mutex mutex_;
  // What each process started is, for the report of its exit: its application, component and
  // the control addresses it serves.
  std::map<ProcessId, protocol::domain::ComponentExitedReport> owners_;
  // The package each process runs inside, kept in the node's cache while it runs.
  std::map<ProcessId, std::shared_ptr<const node::PackageLease>> packages_;
  // Where each process began writing its log (earlier launches' lines come before): the end of
  // its log goes with the report of its exit, its own lines only.
  std::map<ProcessId, std::uint64_t> log_starts_;
  // Every process starts from this thread, which outlives them all (process/spawn_thread.hpp):
  // destroyed after the launcher has stopped them.
  // Started from spawner_ too, and stopped after it (gpp/fork_servers.hpp).
  ForkServers fork_servers_;
  process::SpawnThread spawner_;
  ProcessLauncher launcher_; // last: destroyed (terminating children) first
};

// Registers the GPP under its SPD names.
void register_gpp(node::DeviceRegistry &registry);

} // namespace rsca::gpp
