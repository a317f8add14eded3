// rsca-noded: a node daemon (DeviceManager). Its devices are libraries its DCD's SPDs name
// (node/device_export.hpp), loaded when the node starts; it exports the rsca code they call. Runs
// in the foreground (for systemd and similar supervisors); `rsca domain up` starts it in the
// background.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "common/daemon_heap.hpp"
#include "common/install_layout.hpp"
#include "common/process_priority.hpp"
#include "common/termination_signals.hpp"
#include "dds/participant.hpp"
#include "node/daemon_log.hpp"
#include "node/device_manager.hpp"
#include "profile/descriptor.hpp"
#include "profile/xml_document.hpp"
#include "service/systemd.hpp"

namespace {

// The node's name, from its DCD alone (its devices' profiles are read as the node starts).
rsca::Expected<std::string> node_name_of(const std::string &dcd) {
  auto document = rsca::profile::read_xml_profile(dcd);
  if (!document)
    return tl::unexpected(document.error());
  auto configuration = rsca::profile::read_dcd(*document);
  if (!configuration)
    return tl::unexpected(configuration.error());
  return configuration->name;
}

// The daemon's own log file as well, named by its node (node/daemon_log.hpp): set up before any
// other thread logs. A DCD that cannot be read is left to the node's start to report.
void log_to_file(const std::string &dcd, const std::string &log_dir, std::uint64_t max_bytes) {
  const auto name = node_name_of(dcd);
  if (!name)
    return;
  if (auto ok =
          rsca::node::log_also_to_file(rsca::node::daemon_log_file(log_dir, *name), max_bytes);
      !ok)
    spdlog::warn("this node's log is not kept in a file: {}", ok.error().to_string());
}

} // namespace

int main(int argc, char **argv) {
  const int nice = rsca::run_above_applications(); // before any thread exists
  rsca::TerminationSignals signals;                // before any thread exists
  rsca::bound_daemon_heap();
  const rsca::HeapTrimmer heap_trimmer; // a thread: after the signals are blocked
  CLI::App app{"rsca-noded — an rsca node daemon (DeviceManager)"};
  rsca::node::NodeOptions options;
  std::string dcd, sdrroot, level = "info";
  std::vector<std::string> exec_path;
  std::string log_dir = options.log_dir.string();
  app.add_option("--dcd", dcd, "The node's DCD")->required()->check(CLI::ExistingFile);
  // Of the folders, the last given wins: a service's configuration (RSCA_NODED_ARGS) overrides
  // its unit's (tools/systemd/rsca-noded@.service.in).
  app.add_option("--sdrroot", sdrroot, "SDR root of the DCD (default: found from its location)")
      ->take_last();
  app.add_option("--domain", options.domain_name, "The domain's name")->capture_default_str();
  app.add_option("--exec-path", exec_path,
                 "Folders where component executables named without a path are looked for "
                 "(default: this program's folder and where an install puts rsca's components)");
  app.add_option("--log-dir", log_dir,
                 "Component logs go here, and this daemon's own (rsca-noded.NODE.log)")
      ->capture_default_str()
      ->take_last();
  std::uint64_t log_max_kib = options.log_max_bytes >> 10U;
  app.add_option("--log-max-kib", log_max_kib,
                 "A component's log past this many KiB is rotated, one older file kept (LOG.1), "
                 "as is this daemon's own (rsca-noded.NODE.1.log); 0: never")
      ->capture_default_str();
  auto log_keep_hours = static_cast<std::uint64_t>(options.log_keep.count());
  app.add_option("--log-keep-hours", log_keep_hours,
                 "A component's log that no running process writes (a released application's, a "
                 "failed launch's) is deleted once nothing wrote to it for this many hours "
                 "(1 to 87600)")
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{87600}))
      ->capture_default_str();
  std::string control_socket;
  app.add_option("--control-socket", control_socket,
                 "A Unix socket where local clients (the CLI) reach the domain through this node "
                 "instead of DDS (default: none)")
      ->take_last();
  std::uint32_t ring_kib = options.rings.data_bytes / 1024;
  app.add_option("--ring-kib", ring_kib,
                 "Data in each same-host ring, in KiB (a power of two, 4 to 262144; a sample takes "
                 "at most half)")
      ->capture_default_str();
  app.add_option("--ring-records", options.rings.records,
                 "Records in each same-host ring (a power of two, 16 to 1048576): the most a "
                 "reader may fall behind")
      ->capture_default_str();
  std::string cache_dir;
  app.add_option("--cache-dir", cache_dir,
                 "Where the packages of the processes this node runs are kept, fetched from the "
                 "domain (default: <log-dir>/../cache/<node name>)")
      ->take_last();
  std::uint64_t cache_mib = options.cache.max_bytes >> 20U;
  app.add_option("--cache-mib", cache_mib,
                 "The most the package cache holds, in MiB: packages beyond it are evicted, least "
                 "recently used first, never one a running process is inside")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--log-level", level, "trace, debug, info, warn, error")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  rsca::service::log_to_journal_if_connected("rsca-noded"); // before any thread logs
  spdlog::set_level(spdlog::level::from_str(level));
  spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%l%$ noded: %v");
  log_to_file(dcd, log_dir, log_max_kib << 10U); // after the pattern: the file has its own
  spdlog::info("running at nice {} (components at {})", nice, rsca::application_nice());

  options.dcd = dcd;
  if (ring_kib > (256U << 10U)) {
    spdlog::error("--ring-kib {}: a ring holds at most 262144 KiB", ring_kib);
    return 2;
  }
  options.rings.data_bytes = ring_kib * 1024;
  if (!sdrroot.empty())
    options.sdrroot = sdrroot;
  for (const auto &p : exec_path)
    options.exec_path.emplace_back(p);
  if (options.exec_path.empty())
    options.exec_path = rsca::layout::component_folders();
  options.log_dir = log_dir;
  options.log_max_bytes = log_max_kib << 10U;
  options.log_keep = std::chrono::hours(log_keep_hours);
  options.cache.dir = cache_dir;
  options.cache.max_bytes = cache_mib << 20U;
  if (!control_socket.empty())
    options.control_socket = control_socket;

  const auto dds = rsca::dds::DdsSettings::from_environment();
  rsca::service::notify_status(fmt::format("joining DDS domain {}", dds.domain_id));
  auto participant = rsca::dds::Participant::create(dds);
  if (!participant) {
    spdlog::error("{}", participant.error().to_string());
    return 1;
  }
  rsca::service::notify_status("starting the node of " + dcd + ": its devices, links and cache");
  auto manager = rsca::node::DeviceManager::create(*participant, options);
  if (!manager) {
    spdlog::error("the node cannot start:\n{}", manager.error().to_string());
    return 1;
  }
  // Its devices run, it serves (DDS and its control socket) and it has announced itself: the
  // domain may find it and launch on it from now on.
  const auto &name = (*manager)->node_name();
  rsca::service::notify_ready(fmt::format("serving node {} of domain {} on DDS domain {}", name,
                                          options.domain_name, dds.domain_id));
  const int signal = signals.wait();
  spdlog::info("signal {} received; stopping node {}", signal, name);
  rsca::service::notify_stopping(
      fmt::format("stopping node {} and its processes (signal {})", name, signal));
  return 0;
}
