// The exec parameters of a component process and of a component host: the command line the
// ApplicationFactory writes (to_args) and the component runtime reads (parse_*), in REDHAWK's
// form of key-value pairs. Made and read here only.
//
//   component:  COMPONENT_IDENTIFIER <id> PROFILE_NAME <spd> CONTROL_ADDRESS <address>
//               [NAME_BINDING <name>] [DOMAIN_NAME <domain>] [APPLICATION <name>]
//               [RSCA_CPU <n> RSCA_PRIORITY <n> RSCA_PERIOD_NS <n> ...] [<property id> <value>]...
//   host:       CONTROL_ADDRESS <the host's> then, per component, its parameters as above
//               starting with COMPONENT_IDENTIFIER and naming its LIBRARY <path>.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <tl/expected.hpp>

namespace rsca::protocol {

// What timing admission decided for a periodic component, for it to run by.
struct Schedule {
  unsigned cpu = 0;
  std::uint32_t priority = 0;
  std::chrono::nanoseconds period{0};
  std::chrono::nanoseconds budget{0};
  std::chrono::nanoseconds deadline{0};
};

// RSCA_DDS's value when a connection of the component will go on DDS from its own process (not
// through its node): the process joins DDS as it starts (component/participant_source.hpp).
inline constexpr std::string_view kJoinDds = "join";

struct ExecParams {
  std::string identifier;           // COMPONENT_IDENTIFIER (required)
  std::string name_binding;         // NAME_BINDING (the identifier when absent)
  std::string profile;              // PROFILE_NAME (required)
  std::string domain;               // DOMAIN_NAME
  std::string application;          // APPLICATION
  std::string control_address;      // CONTROL_ADDRESS (required)
  std::string library;              // LIBRARY: a hosted component's, as its SPD names it
  std::string dds;                  // RSCA_DDS: kJoinDds when a connection of its goes on DDS
  std::optional<Schedule> schedule; // RSCA_CPU, RSCA_PRIORITY, RSCA_PERIOD_NS, ... (admission)
  std::vector<std::pair<std::string, std::string>> others; // execparam properties and the rest
};

std::vector<std::string> to_args(const ExecParams &params);
// The exec parameters of argv[1..], in pairs.
tl::expected<ExecParams, std::string> parse_exec_params(int argc, const char *const *argv);

struct HostParams {
  std::string control_address; // the host's own: it serves its components' addresses too
  std::vector<ExecParams> components;
};

std::vector<std::string> to_args(const HostParams &params);
tl::expected<HostParams, std::string> parse_host_params(int argc, const char *const *argv);

// The control addresses a command line names (a host's and its components'): who a process
// serves, for the node that started it.
std::vector<std::string> control_addresses(const std::vector<std::string> &args);

} // namespace rsca::protocol
