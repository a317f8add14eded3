#include "protocol/addresses.hpp"

#include <charconv>

#include <fmt/format.h>

namespace rsca::protocol {

std::string to_string(const LaunchIdentity &launch) {
  return fmt::format("{}.{}", launch.incarnation, launch.number);
}

std::string domain_address(std::string_view domain) {
  return fmt::format("{}/domain", domain);
}

std::string node_address(std::string_view domain, std::string_view node) {
  return fmt::format("{}/node/{}", domain, node);
}

std::string device_address(std::string_view domain, std::string_view node, std::string_view label) {
  return fmt::format("{}/device/{}/{}", domain, node, label);
}

std::string component_address(std::string_view domain, std::string_view application,
                              const LaunchIdentity &launch, std::string_view instance) {
  return fmt::format("{}/component/{}.{}/{}", domain, application, to_string(launch), instance);
}

std::string host_address(std::string_view domain, std::string_view application,
                         const LaunchIdentity &launch, std::string_view device) {
  return fmt::format("{}/host/{}.{}/{}", domain, application, to_string(launch), device);
}

std::string cli_address(std::string_view domain, std::string_view host, long pid, int number) {
  return fmt::format("{}/cli/{}-{}-{}", domain, host, pid, number);
}

std::optional<std::string> cli_clients_partition(std::string_view address) {
  constexpr std::string_view kCli = "/cli/";
  const auto at = address.find(kCli);
  if (at == std::string_view::npos || at == 0 || at + kCli.size() == address.size() ||
      !is_plain_address(address))
    return std::nullopt;
  const std::string_view domain = address.substr(0, at);
  if (domain.find('/') != std::string_view::npos)
    return std::nullopt;
  return fmt::format("{}/cli/*", domain);
}

bool is_plain_address(std::string_view address) {
  return address.find_first_of("*?[]\\") == std::string_view::npos;
}

std::optional<std::uint64_t> incarnation_of(std::string_view address) {
  for (std::string_view kind : {"/component/", "/host/"}) {
    const auto at = address.find(kind);
    if (at == std::string_view::npos)
      continue;
    std::string_view launch = address.substr(at + kind.size());
    launch = launch.substr(0, launch.find('/'));
    const auto last = launch.rfind('.');
    if (last == std::string_view::npos || last == 0)
      return std::nullopt;
    const auto before = launch.rfind('.', last - 1);
    if (before == std::string_view::npos)
      return std::nullopt;
    const std::string_view number = launch.substr(before + 1, last - before - 1);
    std::uint64_t incarnation = 0;
    const auto [end, ec] =
        std::from_chars(number.data(), number.data() + number.size(), incarnation);
    if (ec != std::errc() || end != number.data() + number.size())
      return std::nullopt;
    return incarnation;
  }
  return std::nullopt;
}

} // namespace rsca::protocol
