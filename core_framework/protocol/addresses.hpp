// The address scheme of the control plane: every party's address is made and read here only.
//
//   DOMAIN/domain                                  the domain daemon
//   DOMAIN/node/NODE                               a node daemon (its DeviceManager)
//   DOMAIN/device/NODE/LABEL                       a device a node hosts with component ports
//   DOMAIN/component/APP.INCARNATION.NUMBER/ID     a component of one launch of an application
//   DOMAIN/host/APP.INCARNATION.NUMBER/DEVICE      the component host of that launch on a device
//   DOMAIN/cli/HOST-PID-N                          one CLI client
//
// An application's name may hold dots; the launch's two numbers never do, so an address says
// which incarnation of the domain daemon launched it (incarnation_of).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace rsca::protocol {

// One launch of an application: the domain daemon's incarnation and a number within it.
struct LaunchIdentity {
  std::uint64_t incarnation = 0;
  std::uint64_t number = 0;
};
std::string to_string(const LaunchIdentity &launch); // "INCARNATION.NUMBER"

std::string domain_address(std::string_view domain);
std::string node_address(std::string_view domain, std::string_view node);
std::string device_address(std::string_view domain, std::string_view node, std::string_view label);
std::string component_address(std::string_view domain, std::string_view application,
                              const LaunchIdentity &launch, std::string_view instance);
std::string host_address(std::string_view domain, std::string_view application,
                         const LaunchIdentity &launch, std::string_view device);
std::string cli_address(std::string_view domain, std::string_view host, long pid, int number);

// The partition pattern that matches every CLI client of the domain of `address`, when `address`
// is a CLI client's: a daemon answers all of them through one writer there, because each writer
// it made and deleted would cost it memory for good (Cyclone keeps every endpoint's discovery
// instance). Nothing for any other address.
std::optional<std::string> cli_clients_partition(std::string_view address);

// Whether `address` can name a partition: DDS reads '*' and '?' in one as wildcards (and '[',
// ']', '\\' are kept out as other matchers read them).
bool is_plain_address(std::string_view address);

// The incarnation of the domain daemon that launched the component or host at `address`;
// nothing for any other address.
std::optional<std::uint64_t> incarnation_of(std::string_view address);

} // namespace rsca::protocol
