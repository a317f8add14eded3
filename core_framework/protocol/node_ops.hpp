// The node.* operations: what the domain asks of a node daemon (its DeviceManager), and what a
// node announces of itself.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "protocol/codec.hpp"
#include "protocol/package.hpp"

namespace rsca::protocol::node {

// Where a process may run: the profile's affinity (REDHAWK's exec_directive_class and _value;
// profile/assembly.hpp), which the node resolves on its own host (gpp/affinity.hpp).
struct AffinityDirective {
  static constexpr std::size_t kMaxValue = 256;
  std::string directive; // cpu, socket, nic or nice
  std::string value;     // a CPU or NUMA node list, an interface name, a nice value
  static constexpr auto fields() {
    using R = AffinityDirective;
    return std::tuple{required("directive", &R::directive), required("value", &R::value)};
  }
};

// The one program a node runs by name, with no SPD: rsca's component host, found only in the
// node's own exec path (its hosted components' code comes in the package).
inline constexpr std::string_view kComponentHostProgram = "rsca-component-host";

// Start one process on an executable device: a component, or a component host for several. The
// node runs only an executable of the package (or the component host), inside the package, and
// checks every name that becomes a path (application, component) itself.
struct ExecuteRequest {
  std::string application;
  std::string component; // the component's id, or the host's name: names its log
  std::string device;    // the executable device; empty: the node's first
  std::string entrypoint;
  // Where the SPD is in the package, that the entry point is found from. Empty: the entry point
  // is kComponentHostProgram.
  std::string spd_dir;
  std::vector<std::string> args; // the exec parameters (protocol/exec_params.hpp)
  // The files the process needs: the node runs it inside the package, from its cache, with
  // spd_dir and the paths in args relative to the package. Required: a request without one is
  // refused (optional in the contract only so that the refusal can say why).
  std::optional<Package> package;
  std::optional<std::string> launch; // the launch it is part of (its progress shows transfers)
  std::optional<AffinityDirective> affinity;
  // How long the caller waits for the reply, in ms from the request's arrival: a node whose
  // package fetch outlasts it does not start the process, which nobody would then own (the
  // caller has rolled the launch back). Absent: no limit (an older domain).
  std::optional<std::int64_t> budget_ms;
  static constexpr std::int64_t kMaxBudgetMs = 24LL * 3600 * 1000;
  static constexpr auto fields() {
    using R = ExecuteRequest;
    return std::tuple{
        required("application", &R::application), required("component", &R::component),
        optional("device", &R::device),           required("entrypoint", &R::entrypoint),
        optional("spd_dir", &R::spd_dir),         required("args", &R::args),
        optional("package", &R::package),         optional("launch", &R::launch),
        optional("affinity", &R::affinity),       optional("budget_ms", &R::budget_ms)};
  }
  std::optional<DecodeError> check() const {
    if (budget_ms && (*budget_ms < 0 || *budget_ms > kMaxBudgetMs))
      return DecodeError{"budget_ms", "out of range"};
    return std::nullopt;
  }
};

struct ExecuteReply {
  std::int64_t pid = 0;
  std::string log; // the process's log file
  // Its size when the process started: where this process's lines begin (a log of the same
  // application and component is appended to by each launch).
  std::optional<std::uint64_t> log_offset{};
  static constexpr auto fields() {
    return std::tuple{required("pid", &ExecuteReply::pid), required("log", &ExecuteReply::log),
                      optional("log_offset", &ExecuteReply::log_offset)};
  }
};

struct TerminateRequest {
  std::int64_t pid = 0;
  static constexpr auto fields() { return std::tuple{required("pid", &TerminateRequest::pid)}; }
};

struct TerminateReply {
  std::int64_t pid = 0;
  static constexpr auto fields() { return std::tuple{required("pid", &TerminateReply::pid)}; }
};

// A process's label, APPLICATION/COMPONENT (ProcessRecord), made and read here only. A component
// id holds no '/', so the last one splits it.
inline std::string process_label(std::string_view application, std::string_view component) {
  return fmt::format("{}/{}", application, component);
}
inline std::pair<std::string, std::string> split_process_label(std::string_view label) {
  const auto slash = label.rfind('/');
  if (slash == std::string_view::npos)
    return {std::string(label), {}};
  return {std::string(label.substr(0, slash)), std::string(label.substr(slash + 1))};
}

// A process an executable device runs.
struct ProcessRecord {
  std::int64_t pid = 0;
  std::string label; // APPLICATION/COMPONENT
  std::string log;
  static constexpr auto fields() {
    return std::tuple{required("pid", &ProcessRecord::pid),
                      required("label", &ProcessRecord::label),
                      required("log", &ProcessRecord::log)};
  }
};

// A port of a device that components connect to.
struct DevicePort {
  std::string name;
  std::string direction; // "uses" or "provides"
  std::string repid;
  static constexpr auto fields() {
    return std::tuple{required("name", &DevicePort::name),
                      required("direction", &DevicePort::direction),
                      required("repid", &DevicePort::repid)};
  }
};

// One device of a node, as its node announces it.
struct DeviceRecord {
  std::string id;
  std::string label;
  std::string softpkg;
  std::string kind;                 // "gpp" runs components; "device" is used by them
  Json properties = Json::object(); // matching properties, by name
  Json capacity = Json::object();   // total capacities, by name
  Json allocation = Json::object(); // allocation properties (allocator/plan_json.hpp)
  Json deployer_requires = Json::object();
  std::string address; // a device with ports: where it serves them
  std::vector<DevicePort> ports;
  static constexpr auto fields() {
    using R = DeviceRecord;
    return std::tuple{required("id", &R::id),
                      required("label", &R::label),
                      required("softpkg", &R::softpkg),
                      required("kind", &R::kind),
                      required("properties", &R::properties),
                      required("capacity", &R::capacity),
                      required("allocation", &R::allocation),
                      required("deployerrequires", &R::deployer_requires),
                      optional("address", &R::address),
                      optional("ports", &R::ports)};
  }
};

// A device of the node's DCD that the node did not start (node/device_libraries.hpp: its library
// cannot be loaded, exports no symbol, registers no device of its name; or its SPD names a file
// missing). The node runs without it and says so, so that users see it beside the node.
struct FailedDevice {
  static constexpr std::size_t kMaxName = 256;
  static constexpr std::size_t kMaxPath = 4096; // PATH_MAX
  static constexpr std::size_t kMaxReason = 2 * kMaxPath;
  std::string id;    // NODE:LABEL, as a device it started would have
  std::string label; // the DCD's usage name, else its instantiation id
  std::string softpkg;
  std::string file;   // the library tried (or the file missing); empty when none is named
  std::string symbol; // the symbol looked up in it; empty when it was not looked up
  std::string reason; // names the file and the symbol
  static constexpr auto fields() {
    using R = FailedDevice;
    return std::tuple{required("id", &R::id),           required("label", &R::label),
                      required("softpkg", &R::softpkg), optional("file", &R::file),
                      optional("symbol", &R::symbol),   required("reason", &R::reason)};
  }
  std::optional<DecodeError> check() const {
    if (id.size() > 2 * kMaxName || label.size() > kMaxName || softpkg.size() > kMaxName ||
        symbol.size() > kMaxName)
      return DecodeError{"id", "a name too long"};
    if (file.size() > kMaxPath)
      return DecodeError{"file", "a path too long"};
    if (reason.size() > kMaxReason)
      return DecodeError{"reason", "too long"};
    return std::nullopt;
  }
};

// What a node announces (announcement kind "node").
struct NodeAnnouncement {
  // More than a DCD places (a robot's node has tens of devices).
  static constexpr std::size_t kMaxFailedDevices = 256;
  std::string node;
  std::int64_t pid = 0;
  std::string host;
  std::vector<DeviceRecord> devices;
  // The node relays the control of the processes it starts (protocol/node_link.hpp): the domain
  // calls their components through the node. Absent: a node that does not, whose processes
  // serve their own addresses.
  std::optional<bool> relays_processes;
  // Absent when every device started: a domain of an earlier version, which refuses a field it
  // does not know, still takes the announcement of a node with nothing to report.
  std::optional<std::vector<FailedDevice>> failed_devices;
  static constexpr auto fields() {
    using R = NodeAnnouncement;
    return std::tuple{required("node", &R::node),
                      required("pid", &R::pid),
                      required("host", &R::host),
                      required("devices", &R::devices),
                      optional("relays_processes", &R::relays_processes),
                      optional("failed_devices", &R::failed_devices)};
  }
  std::optional<DecodeError> check() const {
    if (failed_devices && failed_devices->size() > kMaxFailedDevices)
      return DecodeError{"failed_devices", fmt::format("more than {}", kMaxFailedDevices)};
    return std::nullopt;
  }
};

// What the node's shared memory for its host's data holds (node/host_data.hpp).
struct SharedMemoryStatus {
  std::uint64_t rings = 0;  // one per same-host topic
  std::uint64_t ends = 0;   // connections' ends on them
  std::uint64_t pages = 0;  // processes' pages of doorbells
  std::uint64_t bytes = 0;  // of the arena, in use
  std::uint64_t relays = 0; // rings relayed to or from other hosts, a direction each
  static constexpr auto fields() {
    using R = SharedMemoryStatus;
    return std::tuple{required("rings", &R::rings), required("ends", &R::ends),
                      required("pages", &R::pages), required("bytes", &R::bytes),
                      optional("relays", &R::relays)};
  }
};

// What the node's package cache holds (node/package_cache.hpp).
struct PackageCacheStatus {
  std::uint64_t packages = 0;
  std::uint64_t bytes = 0;
  std::uint64_t max_bytes = 0;
  std::uint64_t fetched = 0;       // packages fetched since the node started
  std::uint64_t fetched_bytes = 0; // their bytes that came over the network
  std::uint64_t reused = 0;        // launches that found their package in the cache
  static constexpr auto fields() {
    using R = PackageCacheStatus;
    return std::tuple{
        required("packages", &R::packages),           required("bytes", &R::bytes),
        required("max_bytes", &R::max_bytes),         required("fetched", &R::fetched),
        required("fetched_bytes", &R::fetched_bytes), required("reused", &R::reused)};
  }
};

struct StatusReply {
  std::string node;
  std::int64_t pid = 0;
  std::string host;
  std::vector<DeviceRecord> devices;
  std::vector<ProcessRecord> processes;
  std::optional<SharedMemoryStatus> shared_memory; // none: the node has no shared memory
  std::optional<PackageCacheStatus> cache;
  static constexpr auto fields() {
    using R = StatusReply;
    return std::tuple{
        required("node", &R::node),           required("pid", &R::pid),
        required("host", &R::host),           required("devices", &R::devices),
        required("processes", &R::processes), optional("shared_memory", &R::shared_memory),
        optional("cache", &R::cache)};
  }
};

// A process's figures (process/proc_figures.hpp), for `rsca top`. CPU % is of one CPU (a process
// busy on two is 200) since the node's last reading of that process, or since it started.
struct ProcessFigures {
  static constexpr double kMaxCpuPercent = 100.0 * 4096; // a CPU each, on the largest hosts
  std::int64_t pid = 0;
  double cpu_percent = 0;
  std::uint64_t rss_bytes = 0;
  std::uint64_t threads = 0;
  static constexpr auto fields() {
    using R = ProcessFigures;
    return std::tuple{required("pid", &R::pid), required("cpu_percent", &R::cpu_percent),
                      required("rss_bytes", &R::rss_bytes), required("threads", &R::threads)};
  }
  std::optional<DecodeError> check() const {
    if (pid <= 0)
      return DecodeError{"pid", "not a process id"};
    if (!(cpu_percent >= 0 && cpu_percent <= kMaxCpuPercent)) // NaN too
      return DecodeError{"cpu_percent", "out of range"};
    return std::nullopt;
  }
};

// One process a node's GPP runs, as node.top reports it.
struct TopProcess {
  static constexpr std::size_t kMaxName = 256;
  std::string application;
  std::string component; // the component's id, or the component host's name
  ProcessFigures figures;
  static constexpr auto fields() {
    using R = TopProcess;
    return std::tuple{required("application", &R::application),
                      required("component", &R::component), required("figures", &R::figures)};
  }
  std::optional<DecodeError> check() const {
    if (application.size() > kMaxName || component.size() > kMaxName)
      return DecodeError{"component", "a name too long"};
    return std::nullopt;
  }
};

struct TopReply {
  // More than a node starts (a launch of a hundred components is a hundred processes at most).
  static constexpr std::size_t kMaxProcesses = 4096;
  std::string node;
  std::string host;
  ProcessFigures daemon; // the node daemon itself
  std::vector<TopProcess> processes;
  static constexpr auto fields() {
    using R = TopReply;
    return std::tuple{required("node", &R::node), required("host", &R::host),
                      required("daemon", &R::daemon), required("processes", &R::processes)};
  }
  std::optional<DecodeError> check() const {
    if (processes.size() > kMaxProcesses)
      return DecodeError{"processes", fmt::format("more than {}", kMaxProcesses)};
    if (node.size() > TopProcess::kMaxName || host.size() > TopProcess::kMaxName)
      return DecodeError{"node", "a name too long"};
    return std::nullopt;
  }
};

// The log of a process the node's GPP started (its stdout and stderr), named by its application
// and component (never by a path: the node makes the path in its log folder). A hosted component
// writes to its component host's log: `pid` (app.show's) then finds it among the processes.
struct LogsRequest {
  static constexpr std::uint64_t kMaxBytes = 1ULL << 20U;
  static constexpr std::uint64_t kDefaultBytes = 64ULL << 10U;
  std::string application;
  std::string component;
  std::optional<std::int64_t> pid;
  // Where to read from (a reply's `next`, to follow the log); absent: its last `max_bytes`,
  // from the first whole line.
  std::optional<std::uint64_t> offset;
  std::optional<std::uint64_t> max_bytes; // at most kMaxBytes; absent: kDefaultBytes
  static constexpr auto fields() {
    using R = LogsRequest;
    return std::tuple{required("application", &R::application),
                      required("component", &R::component), optional("pid", &R::pid),
                      optional("offset", &R::offset), optional("max_bytes", &R::max_bytes)};
  }
};

// The node daemon's own log (node/daemon_log.hpp): where to read from and how much, as in
// LogsRequest; the node makes the path.
struct DaemonLogsRequest {
  std::optional<std::uint64_t> offset;
  std::optional<std::uint64_t> max_bytes; // 1 to LogsRequest::kMaxBytes; absent: kDefaultBytes
  static constexpr auto fields() {
    using R = DaemonLogsRequest;
    return std::tuple{optional("offset", &R::offset), optional("max_bytes", &R::max_bytes)};
  }
  // Any offset is one: past the log's end, the log was rotated since (node/process_logs.hpp).
  std::optional<DecodeError> check() const {
    if (max_bytes && (*max_bytes == 0 || *max_bytes > LogsRequest::kMaxBytes))
      return DecodeError{"max_bytes", fmt::format("not 1 to {}", LogsRequest::kMaxBytes)};
    return std::nullopt;
  }
};

// A piece of a log, node.logs's or node.daemon_logs's.
struct LogsReply {
  // The log's name in the node's log folder: APPLICATION/COMPONENT.log, or the daemon's own.
  std::string log;
  std::uint64_t offset = 0; // where `text` starts in the log
  std::uint64_t next = 0;   // where the next read goes on
  std::string text;         // invalid UTF-8 replaced, so that it travels as JSON text
  static constexpr auto fields() {
    using R = LogsReply;
    return std::tuple{required("log", &R::log), required("offset", &R::offset),
                      required("next", &R::next),
                      required("text", &R::text).at_most(LogsRequest::kMaxBytes * 3)};
  }
  std::optional<DecodeError> check() const {
    if (text.size() > LogsRequest::kMaxBytes * 3) // each invalid byte may become 3 (U+FFFD)
      return DecodeError{"text", "longer than asked"};
    if (next < offset)
      return DecodeError{"next", "before offset"};
    return std::nullopt;
  }
};

// rsca echo / rsca hz: a lossy copy of a same-host topic's records (node/topic_tap.hpp), on a
// topic of its own (protocol::tap_topic) with the QoS kTapQos, for as long as the viewer renews
// it: a viewer that stops reading, or dies, never slows the topic's writers or changes the
// connection.
struct TapRequest {
  static constexpr std::size_t kMaxTopic = 512;
  static constexpr std::uint32_t kMaxLeaseMs = 60'000;
  std::string topic; // the connection's topic, which the node's ring carries
  std::string repid; // its port type (component/port_types.hpp)
  std::uint32_t lease_ms = 0;
  static constexpr auto fields() {
    using R = TapRequest;
    return std::tuple{required("topic", &R::topic), required("repid", &R::repid),
                      required("lease_ms", &R::lease_ms)};
  }
  std::optional<DecodeError> check() const {
    if (topic.empty() || topic.size() > kMaxTopic)
      return DecodeError{"topic", fmt::format("empty or longer than {}", kMaxTopic)};
    if (repid.size() > kMaxTopic)
      return DecodeError{"repid", fmt::format("longer than {}", kMaxTopic)};
    if (lease_ms == 0 || lease_ms > kMaxLeaseMs)
      return DecodeError{"lease_ms", fmt::format("not within 1-{}", kMaxLeaseMs)};
    return std::nullopt;
  }
};

struct TapReply {
  std::string tap_topic;
  static constexpr auto fields() { return std::tuple{required("tap_topic", &TapReply::tap_topic)}; }
  std::optional<DecodeError> check() const {
    if (tap_topic.empty() || tap_topic.size() > TapRequest::kMaxTopic * 2)
      return DecodeError{"tap_topic", "empty or too long"};
    return std::nullopt;
  }
};

// The QoS of a tap's writer and its viewers' readers (dds/port_qos.hpp's JSON form): best effort,
// volatile, the newest few: dropped, never waited for, when a viewer is slow.
inline nlohmann::json tap_qos() {
  return {{"reliability", "besteffort"},
          {"durability", "volatile"},
          {"history", "keeplast"},
          {"depth", 64}};
}

struct Execute {
  static constexpr std::string_view name = "node.execute";
  using Request = ExecuteRequest;
  using Reply = ExecuteReply;
};
struct Terminate {
  static constexpr std::string_view name = "node.terminate";
  using Request = TerminateRequest;
  using Reply = TerminateReply;
};
struct Status {
  static constexpr std::string_view name = "node.status";
  using Request = Empty;
  using Reply = StatusReply;
};
struct Top {
  static constexpr std::string_view name = "node.top";
  using Request = Empty;
  using Reply = TopReply;
};
struct Logs {
  static constexpr std::string_view name = "node.logs";
  using Request = LogsRequest;
  using Reply = LogsReply;
};
struct DaemonLogs {
  static constexpr std::string_view name = "node.daemon_logs";
  using Request = DaemonLogsRequest;
  using Reply = LogsReply;
};
struct Tap {
  static constexpr std::string_view name = "node.tap";
  using Request = TapRequest;
  using Reply = TapReply;
};

} // namespace rsca::protocol::node
