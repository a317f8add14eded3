// The domain.* operations: the reports nodes and components send the domain daemon without
// waiting for its reply, and what the CLI asks of the domain as a whole (installs, nodes,
// devices). Applications are in application_ops.hpp, connections and channels in
// connection_ops.hpp.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "protocol/codec.hpp"
#include "protocol/node_ops.hpp"

namespace rsca::protocol::domain {

// A process a node started exited without being asked to.
struct ComponentExitedReport {
  // The end of its log the node sends with it (why a process exits is mostly its last words):
  // whole lines, at most these many and bytes.
  static constexpr std::size_t kMaxLogTailLines = 20;
  static constexpr std::size_t kMaxLogTailBytes = 4096;
  std::string application;
  std::string component;
  std::vector<std::string> addresses; // every component it served: one, or a host's
  std::int64_t pid = 0;
  std::string device;
  std::string status; // "exited with 3", "killed by SIGSEGV"
  std::int32_t exit_code = 0;
  std::int32_t signal = 0;
  std::string log_tail; // the last lines of its log (valid UTF-8); empty: none
  static constexpr auto fields() {
    using R = ComponentExitedReport;
    return std::tuple{required("application", &R::application),
                      required("component", &R::component),
                      required("addresses", &R::addresses),
                      required("pid", &R::pid),
                      required("device", &R::device),
                      required("status", &R::status),
                      optional("exit_code", &R::exit_code),
                      optional("signal", &R::signal),
                      optional("log_tail", &R::log_tail).at_most(kMaxLogTailBytes)};
  }
  std::optional<DecodeError> check() const {
    if (static_cast<std::size_t>(std::count(log_tail.begin(), log_tail.end(), '\n')) >
        kMaxLogTailLines)
      return DecodeError{"log_tail", fmt::format("more than {} lines", kMaxLogTailLines)};
    return std::nullopt;
  }
};

// QoS problems of a provides port's connection since the last report.
struct ConnectionProblemReport {
  std::string application;
  std::string component;
  std::string connection;
  std::string problem; // "deadline missed", "liveliness lost"
  std::int64_t count = 0;
  static constexpr auto fields() {
    using R = ConnectionProblemReport;
    return std::tuple{required("application", &R::application),
                      required("component", &R::component), required("connection", &R::connection),
                      required("problem", &R::problem), required("count", &R::count)};
  }
};

struct ComponentExited {
  static constexpr std::string_view name = "domain.component_exited";
  using Request = ComponentExitedReport;
  using Reply = Empty;
};
struct ConnectionProblem {
  static constexpr std::string_view name = "domain.connection_problem";
  using Request = ConnectionProblemReport;
  using Reply = Empty;
};

// A request or reply that names one thing: an installed application, an event channel.
struct Named {
  std::string name;
  static constexpr auto fields() { return std::tuple{required("name", &Named::name)}; }
};

// One file of an application, carried from the CLI (which may run on another host) with its
// content: a profile as text, a component's code (found beside its SPD) in base64.
enum class FileEncoding : std::uint8_t { Text, Base64 };
} // namespace rsca::protocol::domain

template <>
struct rsca::protocol::EnumNames<rsca::protocol::domain::FileEncoding> {
  using E = domain::FileEncoding;
  static constexpr std::array names{std::pair{E::Text, "text"}, std::pair{E::Base64, "base64"}};
};

namespace rsca::protocol::domain {

// What an install may carry in all, decoded: code bigger than this stays in the domain's exec
// path. A request's frame on a node's control socket holds 16 MiB (kMaxLinkFrame); base64 adds a
// third.
inline constexpr std::uint64_t kMaxInstallBytes = 10ULL << 20U;
// The longest path of an install's file (PATH_MAX): a refusal quotes one whole.
inline constexpr std::size_t kMaxInstallPath = 4096;

struct InstallFile {
  std::string path; // relative to the SDR root the profiles came from
  std::string content;
  std::optional<FileEncoding> encoding; // absent: text
  std::optional<bool> executable;       // absent: false; the file is made executable
  static constexpr auto fields() {
    return std::tuple{
        required("path", &InstallFile::path).at_most(kMaxInstallPath),
        // base64 makes 4 bytes of 3
        required("content", &InstallFile::content).at_most(kMaxInstallBytes / 3 * 4 + 4),
        optional("encoding", &InstallFile::encoding),
        optional("executable", &InstallFile::executable)};
  }
};

struct InstallRequest {
  std::string sad; // the SAD's path among the files
  std::vector<InstallFile> files;
  std::optional<std::string> name; // absent: the SAD's name
  // true (`rsca launch SAD`): refused, replacing nothing, when a launch would refuse the
  // application as its files are (profile::launch_refusals); absent: false, it installs with
  // warnings.
  std::optional<bool> for_launch;
  static constexpr auto fields() {
    return std::tuple{required("sad", &InstallRequest::sad).at_most(kMaxInstallPath),
                      required("files", &InstallRequest::files),
                      optional("name", &InstallRequest::name),
                      optional("for_launch", &InstallRequest::for_launch)};
  }
};

struct InstallReply {
  std::string name;
  std::vector<std::string> warnings; // what the profiles' checks found, as text
  static constexpr auto fields() {
    return std::tuple{required("name", &InstallReply::name),
                      required("warnings", &InstallReply::warnings)};
  }
};

struct InstalledApplication {
  std::string name;
  std::string sad;
  std::uint64_t components = 0;
  static constexpr auto fields() {
    using R = InstalledApplication;
    return std::tuple{required("name", &R::name), required("sad", &R::sad),
                      required("components", &R::components)};
  }
};

struct InstalledReply {
  std::vector<InstalledApplication> applications;
  static constexpr auto fields() {
    return std::tuple{required("applications", &InstalledReply::applications)};
  }
};

struct NodeSummary {
  std::string name;
  std::string address;
  std::int64_t pid = 0;
  std::uint64_t devices = 0;
  // The devices of its DCD it did not start, as it announced them; absent when none.
  std::optional<std::vector<node::FailedDevice>> failed_devices;
  static constexpr auto fields() {
    using R = NodeSummary;
    return std::tuple{required("name", &R::name), required("address", &R::address),
                      required("pid", &R::pid), required("devices", &R::devices),
                      optional("failed_devices", &R::failed_devices)};
  }
};

// An endpoint that announced itself as a node in a form this domain does not take.
struct RefusedNode {
  std::string address;
  std::string why;
  static constexpr auto fields() {
    return std::tuple{required("address", &RefusedNode::address),
                      required("why", &RefusedNode::why)};
  }
};

struct NodesReply {
  std::vector<NodeSummary> nodes; // the nodes that are there: they answer calls
  std::vector<RefusedNode> refused;
  // Nodes whose DDS lease ran out, as they last announced themselves: the domain keeps their
  // devices' reservations until they are back (domain/domain_nodes.cpp), and calls none of them.
  std::vector<NodeSummary> lost;
  static constexpr auto fields() {
    return std::tuple{required("nodes", &NodesReply::nodes),
                      optional("refused", &NodesReply::refused),
                      optional("lost", &NodesReply::lost)};
  }
};

// Every device's capacities (total, allocated, free) and tasks per CPU, as
// allocator/plan_json.hpp makes them: the allocator's view, free-form here.
struct DevicesReply {
  Json devices = Json::array();
  static constexpr auto fields() { return std::tuple{required("devices", &DevicesReply::devices)}; }
};

struct Install {
  static constexpr std::string_view name = "domain.install";
  using Request = InstallRequest;
  using Reply = InstallReply;
};
struct Uninstall {
  static constexpr std::string_view name = "domain.uninstall";
  using Request = Named;
  using Reply = Named;
};
struct Installed {
  static constexpr std::string_view name = "domain.installed";
  using Request = Empty;
  using Reply = InstalledReply;
};
struct Nodes {
  static constexpr std::string_view name = "domain.nodes";
  using Request = Empty;
  using Reply = NodesReply;
};
// The domain daemon's own figures, for `rsca top` (the nodes report theirs: node.top).
struct TopReply {
  std::string host;
  node::ProcessFigures daemon;
  static constexpr auto fields() {
    return std::tuple{required("host", &TopReply::host), required("daemon", &TopReply::daemon)};
  }
};

struct Top {
  static constexpr std::string_view name = "domain.top";
  using Request = Empty;
  using Reply = TopReply;
};
struct Devices {
  static constexpr std::string_view name = "domain.devices";
  using Request = Empty;
  using Reply = DevicesReply;
};

} // namespace rsca::protocol::domain
