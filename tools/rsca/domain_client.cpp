#include "domain_client.hpp"

#include <unistd.h>

#include <atomic>
#include <iostream>

#include <fmt/format.h>

#include "commands.hpp"
#include "exit_codes.hpp"
#include "protocol/addresses.hpp"

namespace rsca::cli {

Expected<DomainClient> DomainClient::connect(const GlobalOptions &global) {
  auto settings = dds::DdsSettings::from_environment();
  settings.trace = "none";
  auto participant = dds::Participant::create(settings);
  if (!participant)
    return tl::unexpected(participant.error());
  char host[128] = {};
  gethostname(host, sizeof(host) - 1);
  static std::atomic<int> counter{0};
  const std::string address = protocol::cli_address(global.domain, host, getpid(), ++counter);
  auto endpoint = control::Endpoint::open(
      *participant, address,
      {.workers = 1, .senders = 4, .on_announcement = {}, .aliases = {}, .prepare_kinds = {}});
  if (!endpoint)
    return tl::unexpected(endpoint.error());
  DomainClient client;
  client.participant_ = *participant;
  client.endpoint_ = std::move(*endpoint);
  client.domain_ = global.domain;
  return client;
}

int exit_code_of(control::Status status) {
  switch (status) {
  case control::Status::Ok:
    return kOk;
  case control::Status::BadRequest:
    return kInvalidProfile;
  case control::Status::NotFound:
    return kNotFound;
  case control::Status::Timeout:
  case control::Status::Unavailable:
    return kUnreachable;
  case control::Status::Rejected:
    return kRejected;
  case control::Status::Failed:
    break;
  }
  return kFailed;
}

int report_failure(const GlobalOptions &global, const std::string &what,
                   const control::CallError &error) {
  std::string message = error.message;
  // The hint only when the domain itself did not answer, not a component during a launch.
  const bool domain_silent =
      message.find(protocol::domain_address(global.domain)) != std::string::npos &&
      message.find("launch of") == std::string::npos;
  if (domain_silent)
    message += fmt::format(" (is the domain \"{}\" up on DDS domain {}? see `rsca domain up`)",
                           global.domain, dds::DdsSettings::from_environment().domain_id);
  if (global.json) {
    control::Json reported{{"status", control::to_string(error.status)}, {"message", message}};
    if (!error.details.empty())
      reported["details"] = error.details;
    print_json({{"error", std::move(reported)}});
  } else {
    fmt::print(stderr, "rsca {}: {}\n", what, message);
    for (const auto &detail : error.details)
      fmt::print(stderr, "  {}\n", detail);
  }
  return exit_code_of(error.status);
}

void print_json(const control::Json &value) {
  std::cout << value.dump(2) << '\n';
}

} // namespace rsca::cli
