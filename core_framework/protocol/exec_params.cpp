#include "protocol/exec_params.hpp"

#include <algorithm>
#include <charconv>
#include <string_view>

#include <fmt/format.h>

namespace rsca::protocol {
namespace {

constexpr std::string_view kIdentifier = "COMPONENT_IDENTIFIER";
constexpr std::string_view kControlAddress = "CONTROL_ADDRESS";

// The schedule's keys, each with its member.
struct ScheduleKey {
  std::string_view key;
  std::uint64_t (*get)(const Schedule &);
  void (*set)(Schedule &, std::uint64_t);
};

constexpr ScheduleKey kScheduleKeys[] = {
    {"RSCA_CPU", [](const Schedule &s) -> std::uint64_t { return s.cpu; },
     [](Schedule &s, std::uint64_t v) { s.cpu = static_cast<unsigned>(v); }},
    {"RSCA_PRIORITY", [](const Schedule &s) -> std::uint64_t { return s.priority; },
     [](Schedule &s, std::uint64_t v) { s.priority = static_cast<std::uint32_t>(v); }},
    {"RSCA_PERIOD_NS",
     [](const Schedule &s) { return static_cast<std::uint64_t>(s.period.count()); },
     [](Schedule &s, std::uint64_t v) { s.period = std::chrono::nanoseconds(v); }},
    {"RSCA_BUDGET_NS",
     [](const Schedule &s) { return static_cast<std::uint64_t>(s.budget.count()); },
     [](Schedule &s, std::uint64_t v) { s.budget = std::chrono::nanoseconds(v); }},
    {"RSCA_DEADLINE_NS",
     [](const Schedule &s) { return static_cast<std::uint64_t>(s.deadline.count()); },
     [](Schedule &s, std::uint64_t v) { s.deadline = std::chrono::nanoseconds(v); }},
};

// Whether `key` is one of the schedule's; an error for a malformed value.
tl::expected<bool, std::string> take_schedule_param(std::string_view key, const std::string &value,
                                                    std::optional<Schedule> &schedule) {
  const auto *field = std::find_if(std::begin(kScheduleKeys), std::end(kScheduleKeys),
                                   [key](const auto &k) { return k.key == key; });
  if (field == std::end(kScheduleKeys))
    return false;
  std::uint64_t number = 0;
  auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), number);
  if (ec != std::errc() || end != value.data() + value.size())
    return tl::unexpected(fmt::format("the exec parameter {} is not a number: \"{}\"", key, value));
  if (!schedule)
    schedule = Schedule{};
  field->set(*schedule, number);
  return true;
}

// The string members and their keys, in the order a command line gives them.
constexpr std::pair<std::string_view, std::string ExecParams::*> kNamed[] = {
    {kIdentifier, &ExecParams::identifier},    {"NAME_BINDING", &ExecParams::name_binding},
    {"PROFILE_NAME", &ExecParams::profile},    {"DOMAIN_NAME", &ExecParams::domain},
    {"APPLICATION", &ExecParams::application}, {kControlAddress, &ExecParams::control_address},
    {"LIBRARY", &ExecParams::library},         {"RSCA_DDS", &ExecParams::dds},
};

} // namespace

std::vector<std::string> to_args(const ExecParams &params) {
  std::vector<std::string> args;
  for (const auto &[key, member] : kNamed)
    if (!(params.*member).empty()) {
      args.emplace_back(key);
      args.push_back(params.*member);
    }
  if (params.schedule)
    for (const auto &k : kScheduleKeys) {
      args.emplace_back(k.key);
      args.push_back(std::to_string(k.get(*params.schedule)));
    }
  for (const auto &[key, value] : params.others) {
    args.push_back(key);
    args.push_back(value);
  }
  return args;
}

tl::expected<ExecParams, std::string> parse_exec_params(int argc, const char *const *argv) {
  ExecParams params;
  if ((argc - 1) % 2 != 0)
    return tl::unexpected(
        fmt::format("exec parameters come in pairs: \"{}\" has no value", argv[argc - 1]));
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string_view key = argv[i];
    std::string value = argv[i + 1];
    const auto *named = std::find_if(std::begin(kNamed), std::end(kNamed),
                                     [key](const auto &n) { return n.first == key; });
    if (named != std::end(kNamed))
      params.*(named->second) = std::move(value);
    else if (auto taken = take_schedule_param(key, value, params.schedule); !taken)
      return tl::unexpected(taken.error());
    else if (!*taken)
      params.others.emplace_back(key, std::move(value));
  }
  for (const auto &[key, value] : {std::pair{kIdentifier, &params.identifier},
                                   std::pair{std::string_view("PROFILE_NAME"), &params.profile},
                                   std::pair{kControlAddress, &params.control_address}})
    if (value->empty())
      return tl::unexpected(fmt::format("the exec parameter {} is missing", key));
  if (params.name_binding.empty())
    params.name_binding = params.identifier;
  return params;
}

std::vector<std::string> to_args(const HostParams &params) {
  std::vector<std::string> args{std::string(kControlAddress), params.control_address};
  for (const auto &component : params.components) {
    auto more = to_args(component);
    args.insert(args.end(), std::make_move_iterator(more.begin()),
                std::make_move_iterator(more.end()));
  }
  return args;
}

tl::expected<HostParams, std::string> parse_host_params(int argc, const char *const *argv) {
  if (argc < 3 || argv[1] != kControlAddress)
    return tl::unexpected(
        fmt::format("the exec parameters start with {} <the host's address>", kControlAddress));
  if (argc < 4 || argv[3] != kIdentifier)
    return tl::unexpected(fmt::format(
        "the host's address is followed by components, each starting with {}", kIdentifier));
  HostParams host{argv[2], {}};
  for (int begin = 3; begin < argc;) {
    int end = begin + 2; // keys stand at every other argument
    while (end < argc && argv[end] != kIdentifier)
      end += 2;
    end = std::min(end, argc);
    std::vector<const char *> group{argv[0]};
    group.insert(group.end(), argv + begin, argv + end);
    auto params = parse_exec_params(static_cast<int>(group.size()), group.data());
    if (!params)
      return tl::unexpected(
          fmt::format("component {}: {}", host.components.size() + 1, params.error()));
    if (params->library.empty())
      return tl::unexpected(
          fmt::format("{}: the exec parameter LIBRARY is missing", params->identifier));
    host.components.push_back(std::move(*params));
    begin = end;
  }
  return host;
}

std::vector<std::string> control_addresses(const std::vector<std::string> &args) {
  std::vector<std::string> addresses;
  for (std::size_t i = 0; i + 1 < args.size(); i += 2)
    if (args[i] == kControlAddress)
      addresses.push_back(args[i + 1]);
  return addresses;
}

} // namespace rsca::protocol
