#include "domain_client.hpp"

#include <grp.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <iostream>
#include <optional>
#include <string_view>

#include <fmt/format.h>

#include <spdlog/spdlog.h>

#include "commands.hpp"
#include "common/host_name.hpp"
#include "control/endpoint.hpp"
#include "control/link_socket.hpp"
#include "control/node_link.hpp"
#include "dds/dds_settings.hpp"
#include "exit_codes.hpp"
#include "protocol/addresses.hpp"
#include "protocol/node_link.hpp"

namespace rsca::cli {

namespace fs = std::filesystem;

fs::path default_run_dir() {
  if (const char *dir = std::getenv("RSCA_RUN_DIR"); dir != nullptr && *dir != '\0')
    return dir;
  // Per DDS domain id and discovery tag: two local domains that differ by either have a folder
  // each, and a CLI finds the node sockets of its own.
  const auto dds = dds::DdsSettings::from_environment();
  return fs::temp_directory_path() /
         (dds.tag.empty() ? fmt::format("rsca-{}-{}", getuid(), dds.domain_id)
                          : fmt::format("rsca-{}-{}-{}", getuid(), dds.domain_id, dds.tag));
}

std::vector<fs::path> node_sockets() {
  if (const char *path = std::getenv("RSCA_NODE_SOCKET"); path != nullptr && *path != '\0') {
    if (std::string_view(path) == "none")
      return {};
    return {path};
  }
  std::vector<fs::path> found;
  std::error_code ec;
  for (const auto &entry : fs::directory_iterator(default_run_dir(), ec))
    if (entry.path().extension() == ".sock" && entry.is_socket(ec))
      found.push_back(entry.path());
  std::sort(found.begin(), found.end());
  return found;
}

namespace {

std::string own_address(const GlobalOptions &global) {
  static std::atomic<int> counter{0};
  return protocol::cli_address(global.domain, host_name(), getpid(), ++counter);
}

// How long a node has to answer the link's hello: a hung node's socket still accepts, and the CLI
// goes on to the next node, or to DDS, instead of waiting out its call.
constexpr std::chrono::milliseconds kNodeHelloTimeout{1000};

// The name of group `gid`, else its number.
std::string group_name(gid_t gid) {
  std::vector<char> buffer(4096);
  group entry{};
  group *found = nullptr;
  if (::getgrgid_r(gid, &entry, buffer.data(), buffer.size(), &found) == 0 && found != nullptr)
    return entry.gr_name;
  return std::to_string(gid);
}

// A node socket that is there but this user may not open: an error saying what to do. Going
// over DDS instead would make the socket's mode protect nothing.
Expected<void> check_may_open(const fs::path &path) {
  if (::access(path.c_str(), R_OK | W_OK) == 0 || errno != EACCES)
    return {};
  struct stat status {};
  const std::string group = ::stat(path.c_str(), &status) == 0 ? group_name(status.st_gid) : "?";
  return make_error({path.string(), 0, 0}, "node socket",
                    fmt::format("this user (uid {}) may not open the node's socket {}: permission "
                                "denied; run rsca as root, or as a member of the socket's group "
                                "{}",
                                ::getuid(), path.string(), group));
}

// A link to the first node socket that accepts one and whose node answers; none when no socket
// is there, or none answers (the CLI then goes over DDS); an error for a socket this user may
// not open.
Expected<std::optional<DomainClient::Link>> link_to_a_node(const std::string &address) {
  namespace link = protocol::link;
  for (const auto &path : node_sockets()) {
    if (auto allowed = check_may_open(path); !allowed)
      return tl::unexpected(allowed.error());
    auto fd = control::connect_link(path.string());
    if (!fd) {
      spdlog::debug("node socket {}: {}", path.string(), fd.error());
      continue;
    }
    auto opened = control::NodeLink::open(std::move(*fd), address, /*workers=*/1);
    if (!opened)
      continue;
    auto hello = (*opened)->call(link::kHelloTarget, link::kHelloOperation, control::Json::object(),
                                 kNodeHelloTimeout);
    if (auto answer = hello.get(); !answer) {
      spdlog::debug("node socket {}: the node does not answer: {}", path.string(),
                    answer.error().message);
      continue;
    }
    return DomainClient::Link{std::move(*opened), path.string()};
  }
  return std::optional<DomainClient::Link>{};
}

} // namespace

Expected<DomainClient> DomainClient::connect(const GlobalOptions &global) {
  const std::string address = own_address(global);
  DomainClient client;
  client.domain_ = global.domain;
  auto link = link_to_a_node(address);
  if (!link)
    return tl::unexpected(link.error());
  if (*link) {
    client.server_ = std::move((*link)->server);
    client.socket_ = std::move((*link)->socket);
    return client;
  }
  auto settings = dds::DdsSettings::from_environment();
  settings.trace = "none";
  auto participant = dds::Participant::create(settings);
  if (!participant)
    return tl::unexpected(participant.error());
  auto endpoint = control::Endpoint::open(
      *participant, address,
      {.workers = 1, .senders = 4, .on_announcement = {}, .aliases = {}, .prepare_kinds = {}});
  if (!endpoint)
    return tl::unexpected(endpoint.error());
  client.participant_ = *participant;
  client.server_ = std::move(*endpoint);
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
    print_json({{"error", std::move(reported)}, {"exit", exit_code_of(error.status)}});
  } else {
    fmt::print(stderr, "rsca {}: {}\n", what, message);
    for (const auto &detail : error.details)
      fmt::print(stderr, "  {}\n", detail);
  }
  return exit_code_of(error.status);
}

int fail(const GlobalOptions &global, std::string_view what, int code, const std::string &message) {
  if (global.json)
    print_json({{"error", {{"status", exit_name(code)}, {"message", message}}}, {"exit", code}});
  else
    fmt::print(stderr, "rsca {}: {}\n", what, message);
  return code;
}

void print_json(const control::Json &value) {
  std::cout << value.dump(2) << '\n';
}

} // namespace rsca::cli
