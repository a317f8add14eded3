#include "component/runtime.hpp"
#include "process/fork_service.hpp"

#include <sched.h>

#include <cerrno>
#include <charconv>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <string_view>

#include <fmt/format.h>
#include <poll.h>
#include <pthread.h>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>
#include <sys/eventfd.h>
#include <sys/prctl.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include "common/exec_environment.hpp"
#include "component/host.hpp"
#include "component/process.hpp"
#include "control/node_link.hpp"

namespace rsca::component {

// ---------------------------------------------------------------------------------------------

namespace {

// Runs the process on the CPU admission chose, so that the analysis holds for what runs.
void pin_to_cpu(unsigned cpu, spdlog::logger &log) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  if (sched_setaffinity(0, sizeof(set), &set) != 0)
    log.warn("cannot run on cpu {} as admitted: {}", cpu, std::strerror(errno));
}

// Its node left it free to run on any CPU (common/exec_environment.hpp).
bool pinning_left_free() {
  const char *pin = std::getenv(kPinAdmittedVariable);
  return pin != nullptr && std::string_view(pin) == "0";
}

} // namespace

namespace {

using detail::ExitEvents;

// Waits for a signal or the release, then shuts the component down.
void wait_for_exit(const ExitEvents &events, detail::Host &host, spdlog::logger &log) {
  int signal = 0;
  // After a release, closing the host waits for the release handler and delivers its reply.
  if (!detail::wait_for_signal_or_release(events, signal))
    return;
  const char *name = signal == SIGINT ? "SIGINT" : "SIGTERM";
  log.info("received {}: shutting down", name);
  host.shutdown(name);
}

int run_host(const ExecParams &params, const ExitEvents &events, const Factory &factory,
             std::shared_ptr<spdlog::logger> logger) {
  auto softpkgs = detail::load_component_profiles({params.profile}, *logger);
  if (!softpkgs) {
    logger->error("{}", softpkgs.error());
    return kExitProfile;
  }
  const auto softpkg = softpkgs->front();
  Context context{params.identifier,
                  params.name_binding,
                  params.application,
                  params.domain,
                  params.profile,
                  params.control_address,
                  logger,
                  params.schedule,
                  params.dds == protocol::kJoinDds};
  if (params.schedule && !pinning_left_free())
    pin_to_cpu(params.schedule->cpu, *logger);
  std::unique_ptr<Component> component;
  try {
    component = factory(context);
  } catch (const std::exception &e) {
    logger->error("constructing the component failed: {}", e.what());
    return kExitFailure;
  }
  detail::Host host(std::move(component), softpkg);
  if (auto prepared = host.prepare(params.others); !prepared) {
    logger->error("the component does not fit its profile:\n{}", prepared.error().to_string());
    return kExitProfile;
  }
  // Started by a node, the process talks to the control plane through it and joins DDS only
  // for a data connection that needs DDS; started otherwise, it opens its own endpoint.
  auto participants = std::make_shared<ParticipantSource>();
  std::shared_ptr<control::Server> server;
  if (auto link = control::NodeLink::inherited()) {
    auto opened = control::NodeLink::open(std::move(*link), params.control_address);
    if (!opened) {
      logger->error("{}", opened.error().to_string());
      return kExitFailure;
    }
    server = std::move(*opened);
  }
  if (auto opened =
          host.open(participants, std::move(server), [&events] { events.notify_released(); });
      !opened) {
    logger->error("{}", opened.error().to_string());
    return kExitFailure;
  }
  logger->info("serving at {}", params.control_address);
  wait_for_exit(events, host, *logger);
  host.close();
  logger->info("exiting");
  return kExitOk;
}

} // namespace

void serve_forks_if_asked(int &argc, char **&argv, std::string_view ready) {
  process::serve_forks_if_asked(argc, argv, ready);
}

namespace {

// `--rsca-describe FILE`, run by the SDK's build (cmake/RscaAddComponent.cmake): constructs the
// component as a launch would and writes what its code declares (profile/code_description.hpp).
int describe_code(const char *file, const Factory &factory) {
  auto logger = spdlog::stderr_logger_st("rsca-describe");
  Context context{"describe", "describe", "", "", {}, "", logger, std::nullopt, false};
  try {
    const auto component = factory(context);
    std::ofstream out(file);
    out << profile::to_json_text(detail::Host::describe(*component)) << "\n";
    if (!out.flush()) {
      logger->error("cannot write {}", file);
      return kExitFailure;
    }
  } catch (const std::exception &e) {
    logger->error("constructing the component failed: {}", e.what());
    return kExitFailure;
  }
  return kExitOk;
}

} // namespace

int run_component(int argc, char **argv, const Factory &factory) {
  if (argc == 3 && std::string_view(argv[1]) == kDescribeOption)
    return describe_code(argv[2], factory);
  return detail::run_process<ExecParams>(
      argc, argv,
      "COMPONENT_IDENTIFIER <id> PROFILE_NAME <spd> CONTROL_ADDRESS <address> [NAME_BINDING "
      "<name>] [DOMAIN_NAME <domain>] [APPLICATION <id>] [<property id> <value>]...",
      parse_exec_params, [](const ExecParams &p) { return p.name_binding; },
      [&factory](const ExecParams &p, const ExitEvents &events, auto logger) {
        return run_host(p, events, factory, std::move(logger));
      });
}

} // namespace rsca::component
