// rsca-domaind: the domain daemon. Runs in the foreground (for systemd and similar supervisors);
// `rsca domain up` starts it in the background.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "common/daemon_heap.hpp"
#include "common/install_layout.hpp"
#include "common/process_priority.hpp"
#include "common/termination_signals.hpp"
#include "dds/participant.hpp"
#include "domain/domain_manager.hpp"
#include "profile/profile_loader.hpp"
#include "service/systemd.hpp"

int main(int argc, char **argv) {
  const int nice = rsca::run_above_applications(); // before any thread exists
  rsca::TerminationSignals signals;                // before any thread exists
  rsca::bound_daemon_heap();
  const rsca::HeapTrimmer heap_trimmer; // a thread: after the signals are blocked
  CLI::App app{"rsca-domaind — the rsca domain daemon (DomainManager, ApplicationFactory, "
               "ResourceAllocator)"};
  std::string dmd;
  std::string repository = "/tmp/rsca/domain";
  std::string level = "info";
  int registration_ms = 10000;
  int call_ms = 5000;
  app.add_option("--dmd", dmd, "The domain's DMD; its name names the domain")
      ->check(CLI::ExistingFile);
  // The last given wins: a service's configuration (RSCA_DOMAIND_ARGS) overrides its unit's.
  app.add_option("--repository", repository, "Where installed applications are kept")
      ->capture_default_str()
      ->take_last();
  app.add_option("--registration-timeout-ms", registration_ms,
                 "How long a launch waits for one more of its components to register")
      ->capture_default_str();
  app.add_option("--call-timeout-ms", call_ms,
                 "How long the domain waits for a node or component to answer a call")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--log-level", level, "trace, debug, info, warn, error")->capture_default_str();
  std::vector<std::string> exec_path;
  app.add_option("--exec-path", exec_path,
                 "Folders where code an SPD names is looked for when its install did not carry it "
                 "(default: this program's folder and where an install puts rsca's components; "
                 "libraries also in ../lib beside each)");
  std::string delivery = "stripped";
  app.add_option("--delivery", delivery,
                 "What nodes get of code files: stripped (without debug information, which the "
                 "domain keeps in <repository>/.build-id; compressed on the wire) or as-is (the "
                 "files themselves, uncompressed)")
      ->check(CLI::IsMember({"stripped", "as-is"}))
      ->capture_default_str();
  std::string strategy = "pack";
  app.add_option("--strategy", strategy,
                 "Placement: pack (fewest devices) or spread (balance load)")
      ->check(CLI::IsMember({"pack", "spread"}))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  rsca::service::log_to_journal_if_connected("rsca-domaind"); // before any thread logs
  spdlog::set_level(spdlog::level::from_str(level));
  spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%l%$ domaind: %v");
  spdlog::info("running at nice {}", nice);

  rsca::domain::DomainOptions options;
  options.repository = repository;
  options.registration_timeout = std::chrono::milliseconds(registration_ms);
  options.call_timeout = std::chrono::milliseconds(call_ms);
  options.strategy = *rsca::allocator::parse_strategy(strategy);
  options.delivery =
      delivery == "as-is" ? rsca::domain::CodeDelivery::AsIs : rsca::domain::CodeDelivery::Stripped;
  for (const auto &p : exec_path)
    options.exec_path.emplace_back(p);
  if (options.exec_path.empty())
    options.exec_path = rsca::layout::component_folders();
  if (!dmd.empty()) {
    rsca::service::notify_status("reading the DMD " + dmd);
    rsca::profile::ProfileLoader loader;
    auto domain = loader.load_domain(dmd);
    if (!domain) {
      spdlog::error("the DMD is invalid:\n{}", domain.error().to_string());
      return 1;
    }
    options.name = domain->name;
  }
  const auto dds = rsca::dds::DdsSettings::from_environment();
  rsca::service::notify_status(fmt::format("joining DDS domain {}", dds.domain_id));
  auto participant = rsca::dds::Participant::create(dds);
  if (!participant) {
    spdlog::error("{}", participant.error().to_string());
    return 1;
  }
  rsca::service::notify_status("opening the domain store in " + repository);
  auto manager = rsca::domain::DomainManager::create(*participant, options);
  if (!manager) {
    spdlog::error("{}", manager.error().to_string());
    return 1;
  }
  // Its store is open and its endpoint serves: a request sent from now on is answered.
  rsca::service::notify_ready(fmt::format("serving domain {} on DDS domain {}, store in {}",
                                          options.name, dds.domain_id, repository));
  const int signal = signals.wait();
  spdlog::info("signal {} received; stopping", signal);
  rsca::service::notify_stopping(fmt::format("stopping (signal {})", signal));
  return 0;
}
