#include "dds/participant.hpp"

#include <map>
#include <mutex>

#include <fmt/format.h>

namespace rsca::dds {

Expected<Entity> checked(dds_entity_t result, std::string_view what) {
  if (result < 0)
    return tl::unexpected(dds_error(result, what));
  return Entity(result);
}

Error dds_error(dds_return_t result, std::string_view what) {
  return Error(
      Diagnostic{{"dds", 0, 0}, "dds", fmt::format("{} failed: {}", what, dds_strretcode(result))});
}

namespace {

// Why a domain could not be created, when its discovery port is the likely reason.
std::string port_hint(std::uint32_t domain_id) {
  constexpr std::uint64_t kLastPort = 65535;
  const std::uint64_t port =
      kFirstDiscoveryPort + std::uint64_t{kDiscoveryPortsPerDomain} * domain_id;
  if (port > kLastPort)
    return fmt::format(" (its discovery port would be {}, past {}; domain ids 0-{} work)", port,
                       kLastPort, kLastPortSafeDomainId);
  if (port >= kFirstEphemeralPort)
    return fmt::format(" (its discovery port {} is among the ephemeral ports another socket may "
                       "hold; domain ids 0-{} avoid them)",
                       port, kLastPortSafeDomainId);
  return {};
}

// Cyclone allows one explicit domain creation per id and process; participants share it.
Expected<std::shared_ptr<Entity>> domain_for(const DdsSettings &settings) {
  static std::mutex mutex;
  static std::map<std::uint32_t, std::weak_ptr<Entity>> domains;
  std::lock_guard lock(mutex);
  if (auto existing = domains[settings.domain_id].lock())
    return existing;
  const std::string config = cyclone_config(settings);
  auto domain = checked(
      dds_create_domain(settings.domain_id, config.c_str()),
      fmt::format("creating DDS domain {}{}", settings.domain_id, port_hint(settings.domain_id)));
  if (!domain)
    return tl::unexpected(domain.error());
  auto shared = std::make_shared<Entity>(std::move(*domain));
  domains[settings.domain_id] = shared;
  return shared;
}

} // namespace

Expected<std::shared_ptr<Participant>> Participant::create(const DdsSettings &settings) {
  auto domain = domain_for(settings);
  if (!domain)
    return tl::unexpected(domain.error());
  auto participant = checked(dds_create_participant(settings.domain_id, nullptr, nullptr),
                             "creating the DDS participant");
  if (!participant)
    return tl::unexpected(participant.error());
  return std::make_shared<Participant>(std::move(*domain), std::move(*participant), settings);
}

} // namespace rsca::dds
