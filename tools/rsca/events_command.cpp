// rsca events: follows the domain's own events live (nodes, devices, applications, components,
// channels); --json prints one JSON object per line, for scripts that follow the domain.
#include <ctime>

#include <fmt/chrono.h>
#include <fmt/format.h>

#include "commands.hpp"
#include "control/domain_events.hpp"
#include "durations.hpp"
#include "exit_codes.hpp"

namespace rsca::cli {
namespace {

std::string local_time(std::uint64_t ns) {
  const auto seconds = static_cast<std::time_t>(ns / 1'000'000'000);
  std::tm tm{};
  localtime_r(&seconds, &tm);
  return fmt::format("{:%H:%M:%S}.{:03}", tm, (ns / 1'000'000) % 1000);
}

void print(const control::DomainEvent &e, bool json) {
  if (json) {
    fmt::print(
        "{}\n",
        nlohmann::json{{"timestamp_ns", e.timestamp_ns}, {"kind", e.kind}, {"details", e.details}}
            .dump());
  } else {
    fmt::print("{}  {:<22} {}\n", local_time(e.timestamp_ns), e.kind, e.details.dump());
  }
  std::fflush(stdout); // a follower reads line by line
}

} // namespace

void add_events_command(CLI::App &app, const GlobalOptions &global, int &exit_code) {
  auto *cmd = app.add_subcommand(
      "events", "Follow the domain's events live (the last ones first); Ctrl-C stops");
  auto count = std::make_shared<int>(0);
  auto wait_ms = std::make_shared<int>(0);
  cmd->add_option("--count", *count, "Stop after this many events");
  add_duration_option(*cmd, "wait", *wait_ms,
                      "Stop when no event came for this long (counted from when the domain is "
                      "found)");
  cmd->callback([count, wait_ms, &global, &exit_code] {
    auto settings = dds::DdsSettings::from_environment();
    settings.trace = "none";
    auto participant = dds::Participant::create(settings);
    if (!participant) {
      fmt::print(stderr, "rsca events: {}\n", participant.error().to_string());
      exit_code = kFailed;
      return;
    }
    auto follower = control::DomainEventFollower::open(*participant, global.domain);
    if (!follower) {
      fmt::print(stderr, "rsca events: {}\n", follower.error().to_string());
      exit_code = kFailed;
      return;
    }
    // The quiet interval of --wait-ms counts from when the domain is found, so that a slow
    // discovery does not pass for a quiet domain.
    if (!(*follower)->wait_for_domain(std::chrono::milliseconds(global.timeout_ms)))
      fmt::print(stderr, "rsca events: no domain {} found within {} ms; waiting for its events\n",
                 global.domain, global.timeout_ms);
    const auto wait =
        *wait_ms > 0 ? std::chrono::milliseconds(*wait_ms) : std::chrono::hours(24 * 365);
    for (int seen = 0; *count == 0 || seen < *count; ++seen) {
      auto event = (*follower)->next(wait);
      if (!event)
        break;
      print(*event, global.json);
    }
    exit_code = kOk;
  });
}

} // namespace rsca::cli
