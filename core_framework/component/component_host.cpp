// The component host: shared-library components of one application on one device, in one process
// (component/runtime.hpp, run_component_host).
#include <dlfcn.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/install_layout.hpp"
#include "component/in_process.hpp"
#include "component/process.hpp"
#include "component/runtime.hpp"
#include "control/node_link.hpp"

namespace rsca::component {

namespace {

namespace fs = std::filesystem;
using detail::ExitEvents;

// Takes LIBRARY out of the group's other parameters.
// The library as the SPD names it: absolute, or relative to the SPD's folder; one that is not
// there is looked up by name where rsca keeps component code (common/install_layout.hpp: the
// example components' libraries, built or installed).
fs::path resolve_library(const fs::path &library, const fs::path &spd) {
  return layout::resolve_code(library, spd, layout::component_folders());
}

// The library stays loaded for the life of the process (RTLD_NODELETE): its code runs on threads
// that may outlive a component's release.
tl::expected<Factory, std::string> load_factory(const fs::path &library) {
  void *handle = dlopen(library.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
  if (handle == nullptr)
    return tl::unexpected(fmt::format("cannot load {}: {}", library.string(), dlerror()));
  auto entry = reinterpret_cast<FactoryExport>(dlsym(handle, kFactorySymbol));
  if (entry == nullptr)
    return tl::unexpected(
        fmt::format("{} exports no {} (declare the component with RSCA_COMPONENT)",
                    library.string(), kFactorySymbol));
  Factory factory;
  entry(&factory);
  return factory;
}

Context context_of(const ExecParams &p) {
  return Context{p.identifier,
                 p.name_binding,
                 p.application,
                 p.domain,
                 p.profile,
                 p.control_address,
                 in_process_logger(p.name_binding),
                 p.schedule,
                 p.dds == protocol::kJoinDds};
}

// The host's one control presence, serving every component's address too: its link to the node
// that started it, else an endpoint of its own on DDS. Its workers run the batches of calls the
// domain sends for all the host's components at once.
Expected<std::shared_ptr<control::Server>> open_server(const HostParams &host,
                                                       ParticipantSource &participants) {
  if (auto link = control::NodeLink::inherited()) {
    auto opened = control::NodeLink::open(std::move(*link), host.control_address);
    if (!opened)
      return tl::unexpected(opened.error());
    return std::shared_ptr<control::Server>(std::move(*opened));
  }
  auto participant = participants.get();
  if (!participant)
    return tl::unexpected(participant.error());
  control::EndpointOptions options{
      .workers = 4, .senders = 2, .on_announcement = {}, .aliases = {}, .prepare_kinds = {}};
  for (const auto &h : host.components)
    options.aliases.push_back(h.control_address);
  auto endpoint = control::Endpoint::open(*participant, host.control_address, options);
  if (!endpoint)
    return tl::unexpected(endpoint.error());
  return std::shared_ptr<control::Server>(std::move(*endpoint));
}

int serve_hosted(const HostParams &host, const ExitEvents &events, spdlog::logger &log) {
  const auto &hosted = host.components;
  std::vector<std::string> spds;
  for (const auto &h : hosted)
    spds.push_back(h.profile);
  auto softpkgs = detail::load_component_profiles(spds, log);
  if (!softpkgs) {
    log.error("{}", softpkgs.error());
    return kExitProfile;
  }
  auto participants = std::make_shared<ParticipantSource>();
  auto endpoint = open_server(host, *participants);
  if (!endpoint) {
    log.error("{}", endpoint.error().to_string());
    return kExitFailure;
  }
  std::atomic<std::size_t> unreleased{hosted.size()};
  const auto on_released = [&unreleased, &events] {
    if (--unreleased == 0)
      events.notify_released();
  };
  std::vector<std::unique_ptr<InProcessComponent>> components;
  for (std::size_t i = 0; i < hosted.size(); ++i) {
    const auto &h = hosted[i];
    auto factory = load_factory(resolve_library(h.library, h.profile));
    if (!factory) {
      log.error("{}: {}", h.identifier, factory.error());
      return kExitFailure;
    }
    auto component = InProcessComponent::open(*factory, context_of(h), (*softpkgs)[i], participants,
                                              h.others, on_released, *endpoint);
    if (!component) {
      log.error("{}: {}", h.identifier, component.error().to_string());
      return kExitProfile;
    }
    components.push_back(std::move(*component));
  }
  log.info("hosting {} component(s)", components.size());
  int signal = 0;
  if (detail::wait_for_signal_or_release(events, signal))
    log.info("received {}: shutting down", signal == SIGINT ? "SIGINT" : "SIGTERM");
  components.clear(); // each is stopped, released and withdrawn
  endpoint->reset();
  log.info("exiting");
  return kExitOk;
}

} // namespace

int run_component_host(int argc, char **argv) {
  return detail::run_process<HostParams>(
      argc, argv,
      "CONTROL_ADDRESS <address> (COMPONENT_IDENTIFIER <id> PROFILE_NAME <spd> CONTROL_ADDRESS "
      "<address> LIBRARY <path> [NAME_BINDING <name>] [DOMAIN_NAME <domain>] [APPLICATION <id>] "
      "[<property id> <value>]...)...",
      parse_host_params,
      [](const HostParams &host) {
        return fmt::format("host:{}", host.components.front().application);
      },
      [](const HostParams &host, const ExitEvents &events, auto logger) {
        return serve_hosted(host, events, *logger);
      });
}

} // namespace rsca::component
