// The app.* operations: what the CLI asks the domain daemon of applications (plan, launch and
// its progress, start, stop, release, configure, query, list, show).
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "protocol/codec.hpp"
#include "protocol/component_ops.hpp"
#include "protocol/connection_ops.hpp"
#include "protocol/domain_ops.hpp"

namespace rsca::protocol {
namespace application {

// A component's life as the domain sees it, in the order a launch and a release pass through.
// Exited is final while the application runs: a component that exited is never called again.
// Unreachable is not: its node was lost (a network partition, or the node died), and when the
// node is back the component is running again if its process lived on, else exited.
enum class ComponentState : std::uint8_t {
  Allocated,  // placed, its device's capacity reserved
  Executed,   // its process started
  Registered, // it announced itself and was configured and connected
  Running,
  Stopped,
  Exited, // its process ended without being asked to
  Released,
  Unreachable // its node is lost; it may still run
};

} // namespace application

template <>
struct EnumNames<application::ComponentState> {
  using S = application::ComponentState;
  static constexpr std::array names{
      std::pair{S::Allocated, "allocated"},   std::pair{S::Executed, "executed"},
      std::pair{S::Registered, "registered"}, std::pair{S::Running, "running"},
      std::pair{S::Stopped, "stopped"},       std::pair{S::Exited, "exited"},
      std::pair{S::Released, "released"},     std::pair{S::Unreachable, "unreachable"}};
};

} // namespace rsca::protocol

namespace rsca::protocol::application {

// Admission and placement of an installed application, as app.plan and app.create take them.
struct PlanRequest {
  std::string application;                   // the installed application
  std::map<std::string, std::string> assign; // component instantiation -> device id
  std::optional<std::string> strategy;       // "pack" or "spread"; absent: the domain's
  static constexpr auto fields() {
    using R = PlanRequest;
    return std::tuple{required("application", &R::application), optional("assign", &R::assign),
                      optional("strategy", &R::strategy)};
  }
};

// Admission and placement of an application that is not installed (`rsca plan SAD`): its files,
// as an install carries them, which the domain reads aside and removes once planned. A dry run:
// nothing is installed or reserved.
struct PlanFilesRequest {
  domain::InstallRequest files;
  std::map<std::string, std::string> assign;
  std::optional<std::string> strategy;
  static constexpr auto fields() {
    using R = PlanFilesRequest;
    return std::tuple{required("files", &R::files), optional("assign", &R::assign),
                      optional("strategy", &R::strategy)};
  }
};

// The allocator's answer: a plan when admitted, else the rejections per component, both as
// allocator/plan_json.hpp makes them (also offline, by `rsca plan --node`).
struct PlanReply {
  bool admitted = false;
  std::string strategy;
  std::optional<Json> plan;
  std::optional<Json> rejections;
  static constexpr auto fields() {
    using R = PlanReply;
    return std::tuple{required("admitted", &R::admitted), required("strategy", &R::strategy),
                      optional("plan", &R::plan), optional("rejections", &R::rejections)};
  }
};

struct CreateRequest : PlanRequest {
  std::optional<std::string> name;      // the running application's; absent: the installed name
  std::optional<std::string> launch_id; // for app.progress and app.cancel; absent: the name
  bool start = true;                    // false: create and connect only
  // The launch settles the install made for it (`rsca launch SAD`): kept when it launches, else
  // what it replaced is put back (InstalledRepository::settle). Absent: false.
  std::optional<bool> settles_install;
  static constexpr auto fields() {
    using R = CreateRequest;
    return std::tuple_cat(
        PlanRequest::fields(),
        std::tuple{optional("name", &R::name), optional("launch_id", &R::launch_id),
                   optional("start", &R::start), optional("settles_install", &R::settles_install)});
  }
};

struct StepView {
  std::string step;   // "check", "allocate", "execute", "register", ...
  std::string detail; // what was done; "failed" for the step that failed
  double ms = 0;
  static constexpr auto fields() {
    return std::tuple{required("step", &StepView::step), required("detail", &StepView::detail),
                      required("ms", &StepView::ms)};
  }
};

// One component of a running application.
struct ComponentView {
  std::string id; // its componentinstantiation id
  std::string usage_name;
  std::string node;
  std::string device;
  std::string implementation;
  std::string address; // its control endpoint
  std::int64_t pid = 0;
  ComponentState state = ComponentState::Allocated;
  bool assembly_controller = false;
  std::optional<Json> schedule; // a periodic component's: allocator/plan_json.hpp's form
  static constexpr auto fields() {
    using R = ComponentView;
    return std::tuple{required("id", &R::id),
                      required("usage_name", &R::usage_name),
                      required("node", &R::node),
                      required("device", &R::device),
                      required("implementation", &R::implementation),
                      required("address", &R::address),
                      required("pid", &R::pid),
                      required("state", &R::state),
                      required("assembly_controller", &R::assembly_controller),
                      optional("schedule", &R::schedule)};
  }
};

// One connection of a running application's SAD.
struct SadConnectionView {
  std::string id;
  std::string uses; // "owner.port"; empty: an event channel's publisher side
  std::string provides;
  std::string repid;
  std::string topic;         // empty: a uses port calling a component's supported interface
  Json qos = Json::object(); // dds/port_qos.hpp's JSON form
  // Each end as a typed port (a component's, with the application, or a device's; a supported
  // interface's port is empty); absent: the event channel's side.
  std::optional<connection::PortEnd> uses_end;
  std::optional<connection::PortEnd> provides_end;
  std::optional<std::string> channel; // the event channel it joins; absent: none
  std::optional<std::string> filter;  // its provides end's content filter; absent: none
  // Live, as its ends' owners report it when app.show asks; absent: an end did not answer.
  std::optional<connection::ConnectionState> state;
  static constexpr auto fields() {
    using R = SadConnectionView;
    return std::tuple{required("id", &R::id),
                      required("uses", &R::uses),
                      required("provides", &R::provides),
                      required("repid", &R::repid),
                      required("topic", &R::topic),
                      required("qos", &R::qos),
                      optional("uses_end", &R::uses_end),
                      optional("provides_end", &R::provides_end),
                      optional("channel", &R::channel),
                      optional("filter", &R::filter),
                      optional("state", &R::state)};
  }
};

// A port of a component that the application's SAD offers outside it (<externalports>).
struct ExternalPortView {
  std::string name;
  std::string component;
  std::string port; // the component's port, or the supported interface's repid
  std::string kind; // "uses", "provides" or "supportedinterface"
  static constexpr auto fields() {
    using R = ExternalPortView;
    return std::tuple{required("name", &R::name), required("component", &R::component),
                      required("port", &R::port), required("kind", &R::kind)};
  }
};

// A running application.
struct ApplicationView {
  std::string name;
  std::string installed;
  std::string sad;
  std::string state; // "created", "running", "stopped", "failed", or "degraded"
  std::vector<std::string> exited;
  std::vector<ComponentView> components;
  std::vector<SadConnectionView> connections;
  std::vector<ExternalPortView> external_ports; // absent from a reply: none
  static constexpr auto fields() {
    using R = ApplicationView;
    return std::tuple{required("name", &R::name),
                      required("installed", &R::installed),
                      required("sad", &R::sad),
                      required("state", &R::state),
                      required("exited", &R::exited),
                      required("components", &R::components),
                      required("connections", &R::connections),
                      optional("external_ports", &R::external_ports)};
  }
};

struct LaunchReport {
  std::vector<StepView> steps;
  double ms = 0;
  static constexpr auto fields() {
    return std::tuple{required("steps", &LaunchReport::steps), required("ms", &LaunchReport::ms)};
  }
};

struct CreateReply : ApplicationView {
  LaunchReport launch;
  static constexpr auto fields() {
    return std::tuple_cat(ApplicationView::fields(),
                          std::tuple{required("launch", &CreateReply::launch)});
  }
};

struct LaunchId {
  std::string launch_id;
  static constexpr auto fields() { return std::tuple{required("launch_id", &LaunchId::launch_id)}; }
};

struct ProgressReply {
  std::vector<StepView> steps;
  bool done = false;
  std::optional<std::uint64_t> delivered_bytes;      // files the nodes fetched for it so far
  std::optional<std::uint64_t> delivered_wire_bytes; // what they took on the wire (compressed)
  static constexpr auto fields() {
    return std::tuple{required("steps", &ProgressReply::steps),
                      required("done", &ProgressReply::done),
                      optional("delivered_bytes", &ProgressReply::delivered_bytes),
                      optional("delivered_wire_bytes", &ProgressReply::delivered_wire_bytes)};
  }
};

struct CancelReply {
  bool cancelled = false; // false: it had finished
  bool done = false;
  std::optional<bool> begun; // when cancelled; false: its create had not come yet
  static constexpr auto fields() {
    return std::tuple{required("cancelled", &CancelReply::cancelled),
                      required("done", &CancelReply::done), optional("begun", &CancelReply::begun)};
  }
};

// A request that names one running application.
struct AppRequest {
  std::string app;
  static constexpr auto fields() { return std::tuple{required("app", &AppRequest::app)}; }
};

// A component of a released application whose node is lost: its process could not be ended,
// and is ended when its node is back.
struct LostComponent {
  std::string component;
  std::string node;
  static constexpr auto fields() {
    return std::tuple{required("component", &LostComponent::component),
                      required("node", &LostComponent::node)};
  }
};

struct ReleaseReply {
  std::string name;
  std::vector<std::string> unconfirmed; // components its node terminated
  // Components whose node is lost: to be ended when it is back. Absent when there are none: a
  // CLI of an earlier version, which refuses a field it does not know, still reads the reply.
  std::optional<std::vector<LostComponent>> to_end_later;
  static constexpr auto fields() {
    return std::tuple{required("name", &ReleaseReply::name),
                      required("unconfirmed", &ReleaseReply::unconfirmed),
                      optional("to_end_later", &ReleaseReply::to_end_later)};
  }
};

// Where app.configure and app.query go: a device (NODE:DEVICE), or else an application's
// component (empty or absent: its assembly controller).
struct Target {
  std::optional<std::string> device;
  std::optional<std::string> app;
  std::optional<std::string> component;
  static constexpr auto fields() {
    return std::tuple{optional("device", &Target::device), optional("app", &Target::app),
                      optional("component", &Target::component)};
  }
};

struct ConfigureRequest : Target {
  // Values as text (the CLI's prop=value), typed by the domain against the component's PRF.
  std::optional<std::map<std::string, Json>> values;
  // Values already typed (profile/property_json.hpp); `values` override them.
  std::optional<std::map<std::string, Json>> properties;
  static constexpr auto fields() {
    using R = ConfigureRequest;
    return std::tuple_cat(Target::fields(), std::tuple{optional("values", &R::values),
                                                       optional("properties", &R::properties)});
  }
};

// What a configure set: the id as the request named it (an external property's id, or the
// component's own), the component it reached and its property id there, and the typed value.
struct ConfiguredProperty {
  std::string id;
  std::string component; // empty for a device
  std::string property;
  Json value;
  static constexpr auto fields() {
    using C = ConfiguredProperty;
    return std::tuple{required("id", &C::id), required("component", &C::component),
                      required("property", &C::property), required("value", &C::value)};
  }
};

struct ConfigureReply {
  std::vector<ConfiguredProperty> set;
  static constexpr auto fields() { return std::tuple{required("set", &ConfigureReply::set)}; }
};

struct QueryRequest : Target {
  std::vector<std::string> ids; // none: every property
  static constexpr auto fields() {
    return std::tuple_cat(Target::fields(), std::tuple{optional("ids", &QueryRequest::ids)});
  }
};

struct ApplicationSummary {
  std::string name;
  std::string installed;
  std::string state;
  std::vector<std::string> exited;
  std::uint64_t components = 0;
  std::vector<std::string> unreachable; // on a node that is lost
  static constexpr auto fields() {
    using R = ApplicationSummary;
    return std::tuple{required("name", &R::name),
                      required("installed", &R::installed),
                      required("state", &R::state),
                      required("exited", &R::exited),
                      required("components", &R::components),
                      optional("unreachable", &R::unreachable)};
  }
};

// A component process that no application of this run of the domain daemon launched.
struct UnknownComponent {
  std::string address;
  std::string application;
  std::string component;
  std::int64_t pid = 0;
  static constexpr auto fields() {
    using R = UnknownComponent;
    return std::tuple{required("address", &R::address), required("application", &R::application),
                      required("component", &R::component), required("pid", &R::pid)};
  }
};

struct ListReply {
  std::vector<ApplicationSummary> applications;
  std::vector<UnknownComponent> unknown;
  static constexpr auto fields() {
    return std::tuple{required("applications", &ListReply::applications),
                      required("unknown", &ListReply::unknown)};
  }
};

// A launch that failed, as the domain remembers it (the last kKept): which process each of its
// components had on which node, so that their logs stay reachable after the rollback
// (`rsca logs --failed`, which asks each node for them as for a running component's).
struct FailedProcess {
  std::string component; // its instance id
  std::string node;
  std::int64_t pid = 0;
  std::string log; // the name its log has on its node: its own id, or its component host's
  // Where this process began writing its log (the file holds earlier launches' lines before).
  std::optional<std::uint64_t> log_offset{};
  static constexpr auto fields() {
    using R = FailedProcess;
    return std::tuple{required("component", &R::component), required("node", &R::node),
                      required("pid", &R::pid), required("log", &R::log),
                      optional("log_offset", &R::log_offset)};
  }
};

struct FailedLaunch {
  static constexpr std::size_t kKept = 16;
  static constexpr std::size_t kMaxError = 64U << 10U;
  std::string application; // the running application's name
  std::string installed;
  std::string launch_id;
  std::string step;
  std::string error;
  std::int64_t failed_at_ms = 0;         // since the Unix epoch
  std::vector<FailedProcess> components; // those that had a process
  static constexpr auto fields() {
    using R = FailedLaunch;
    return std::tuple{required("application", &R::application),
                      required("installed", &R::installed),
                      required("launch_id", &R::launch_id),
                      required("step", &R::step),
                      required("error", &R::error).at_most(kMaxError),
                      required("failed_at_ms", &R::failed_at_ms),
                      required("components", &R::components)};
  }
};

// The failed launches of one application (absent: of all), oldest first.
struct FailedRequest {
  std::optional<std::string> application;
  static constexpr auto fields() {
    return std::tuple{optional("application", &FailedRequest::application)};
  }
};

struct FailedReply {
  std::vector<FailedLaunch> launches;
  static constexpr auto fields() {
    return std::tuple{required("launches", &FailedReply::launches).at_most(FailedLaunch::kKept)};
  }
};

struct Plan {
  static constexpr std::string_view name = "app.plan";
  using Request = PlanRequest;
  using Reply = PlanReply;
};
struct PlanFiles {
  static constexpr std::string_view name = "app.plan_files";
  using Request = PlanFilesRequest;
  using Reply = PlanReply;
};
struct Create {
  static constexpr std::string_view name = "app.create";
  using Request = CreateRequest;
  using Reply = CreateReply;
};
struct Progress {
  static constexpr std::string_view name = "app.progress";
  using Request = LaunchId;
  using Reply = ProgressReply;
};
struct Cancel {
  static constexpr std::string_view name = "app.cancel";
  using Request = LaunchId;
  using Reply = CancelReply;
};
struct Release {
  static constexpr std::string_view name = "app.release";
  using Request = AppRequest;
  using Reply = ReleaseReply;
};
struct Start {
  static constexpr std::string_view name = "app.start";
  using Request = AppRequest;
  using Reply = ApplicationView;
};
struct Stop {
  static constexpr std::string_view name = "app.stop";
  using Request = AppRequest;
  using Reply = ApplicationView;
};
// Answered as the component (or device) answers component.configure and component.query.
struct Configure {
  static constexpr std::string_view name = "app.configure";
  using Request = ConfigureRequest;
  using Reply = ConfigureReply;
};
struct Query {
  static constexpr std::string_view name = "app.query";
  using Request = QueryRequest;
  using Reply = component::QueryReply;
};
struct List {
  static constexpr std::string_view name = "app.list";
  using Request = Empty;
  using Reply = ListReply;
};
struct Show {
  static constexpr std::string_view name = "app.show";
  using Request = AppRequest;
  using Reply = ApplicationView;
};
struct Failed {
  static constexpr std::string_view name = "app.failed";
  using Request = FailedRequest;
  using Reply = FailedReply;
};

} // namespace rsca::protocol::application
