#include "component/in_process.hpp"

#include <spdlog/spdlog.h>

#include "component/host.hpp"

namespace rsca::component {

InProcessComponent::InProcessComponent(std::unique_ptr<detail::Host> host, std::string address)
    : host_(std::move(host)), address_(std::move(address)) {}

InProcessComponent::~InProcessComponent() {
  host_->shutdown("its owner stops");
  host_->close();
}

Expected<std::unique_ptr<InProcessComponent>>
InProcessComponent::open(const Factory &factory, Context context,
                         std::shared_ptr<const profile::ResolvedSoftPkg> softpkg,
                         std::shared_ptr<ParticipantSource> participants,
                         const std::vector<std::pair<std::string, std::string>> &execparams,
                         std::function<void()> on_released,
                         std::shared_ptr<control::Server> server) {
  const std::string address = context.control_address;
  const std::string where = softpkg->spd_path.string();
  std::unique_ptr<Component> component;
  try {
    component = factory(context);
  } catch (const std::exception &e) {
    return make_error({where, 0, 0}, "component", e.what());
  }
  auto host = std::make_unique<detail::Host>(std::move(component), std::move(softpkg));
  if (auto prepared = host->prepare(execparams); !prepared)
    return tl::unexpected(prepared.error());
  // A device in its node gets an endpoint of its own with few threads: its operations come one
  // at a time, and one more worker serves a call while another waits (component.await_matched).
  const control::EndpointOptions options{
      .workers = 2, .senders = 1, .on_announcement = {}, .aliases = {}, .prepare_kinds = {}};
  if (auto opened =
          host->open(std::move(participants), std::move(server), std::move(on_released), options);
      !opened)
    return tl::unexpected(opened.error());
  return std::unique_ptr<InProcessComponent>(new InProcessComponent(std::move(host), address));
}

Expected<void> InProcessComponent::bring_up(const control::Json &properties) {
  return host_->bring_up(properties);
}

std::vector<protocol::node::DevicePort> InProcessComponent::ports() const {
  return host_->ports();
}

std::shared_ptr<spdlog::logger> in_process_logger(const std::string &name) {
  const auto &sinks = spdlog::default_logger()->sinks();
  auto logger = std::make_shared<spdlog::logger>(name, sinks.begin(), sinks.end());
  logger->set_level(spdlog::default_logger()->level());
  return logger;
}

} // namespace rsca::component
