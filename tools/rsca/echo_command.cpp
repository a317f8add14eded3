// rsca echo PORT and rsca hz PORT: the samples a port's connection carries as they flow, or their
// rate and gaps (issue 39 item 9). PORT is APP/COMPONENT.PORT or APP.PORT (an external port, or a
// port name one component of the application has).
//
// Nothing of the connection changes: a same-host connection (the node's ring) is seen through a
// tap of the writer's node (node.tap, node/topic_tap.hpp), a DDS connection by a best-effort
// volatile reader of its topic. Either way the viewer is lossy, and a slow or stopped viewer never
// holds the writer back; an in-host or TCP connection has no place a viewer can join, and is
// refused with the reason.
#include <algorithm>
#include <chrono>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "commands.hpp"
#include "common/units.hpp"
#include "component/sample_view.hpp"
#include "dds/port_qos.hpp"
#include "domain_client.hpp"
#include "exit_codes.hpp"
#include "protocol/application_ops.hpp"
#include "protocol/connection_ops.hpp"
#include "protocol/node_ops.hpp"
#include "protocol/topics.hpp"
#include "value_text.hpp"

namespace rsca::cli {
namespace {

namespace app_ops = protocol::application;
namespace connection_ops = protocol::connection;
namespace node_ops = protocol::node;
using control::Json;
using Clock = std::chrono::steady_clock;

// A tap's lease, renewed every third of it: a viewer that dies leaves it open that long at most.
constexpr std::chrono::milliseconds kTapLease{3000};

// Where a port's samples are seen.
struct PortSource {
  std::string connection;
  std::string topic; // the DDS topic the viewer reads
  std::string repid;
  Json qos;               // the viewer reader's
  std::string tap_node;   // the node whose tap it renews; empty: the connection's own DDS topic
  std::string ring_topic; // what the tap copies
};

struct ViewOptions {
  std::string target;
  int count = 0;             // echo: samples; hz: windows; 0: until interrupted
  std::string wait = "10s";  // the longest without a sample
  std::string window = "5s"; // hz
  bool full = false;         // echo: long values whole
};

struct Failure {
  int code;
  std::string message;
};
template <typename T>
using Resolved = tl::expected<T, Failure>;

// APP/COMPONENT.PORT or APP.PORT.
struct PortName {
  std::string app, component, port;
};
std::optional<PortName> parse_port(const std::string &target) {
  const auto dot = target.rfind('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == target.size())
    return std::nullopt;
  PortName name{target.substr(0, dot), "", target.substr(dot + 1)};
  if (const auto slash = name.app.find('/'); slash != std::string::npos) {
    name.component = name.app.substr(slash + 1);
    name.app.resize(slash);
  }
  return name;
}

// The port's end "COMPONENT.PORT" as connection.list names it.
bool end_is(const std::string &end, const PortName &name) {
  const auto dot = end.rfind('.');
  if (dot == std::string::npos || end.substr(dot + 1) != name.port)
    return false;
  return name.component.empty() || end.substr(0, dot) == name.component;
}

std::string node_of(const app_ops::ApplicationView &app, const std::string &end) {
  const std::string component = end.substr(0, end.rfind('.'));
  for (const auto &c : app.components)
    if (c.id == component)
      return c.node;
  return {};
}

Resolved<PortSource> source_of(const connection_ops::ListedConnection &c,
                               const app_ops::ApplicationView &app) {
  const Json &uses = c.uses_state;
  const auto flag = [&uses](const char *key) { return uses.is_object() && uses.value(key, false); };
  if (flag("in_host"))
    return tl::unexpected(Failure{
        kRejected, fmt::format("connection {} runs inside one component host process (in-host): "
                               "no viewer can join it",
                               c.id)});
  if (flag("tcp"))
    return tl::unexpected(Failure{
        kRejected, fmt::format("connection {} is a TCP stream between two processes: no viewer "
                               "can join it",
                               c.id)});
  Json qos = node_ops::tap_qos();
  if (flag("same_host")) {
    const std::string node = node_of(app, c.uses);
    if (node.empty())
      return tl::unexpected(Failure{
          kNotFound, fmt::format("connection {}: the node of {} is not known", c.id, c.uses)});
    return PortSource{c.id, "", c.repid, std::move(qos), node, c.topic};
  }
  // The connection's own topic: the reader must not refuse its writer's ownership.
  if (c.qos.is_object() && c.qos.contains("ownership"))
    qos["ownership"] = c.qos.at("ownership");
  return PortSource{c.id, c.topic, c.repid, std::move(qos), "", ""};
}

Resolved<PortSource> resolve(const DomainClient &client, const PortName &name,
                             std::chrono::milliseconds timeout) {
  auto app = client.call<app_ops::Show>({name.app}, timeout);
  if (!app)
    return tl::unexpected(Failure{exit_code_of(app.error().status), app.error().message});
  PortName wanted = name;
  if (wanted.component.empty()) // an external port names its component's port
    for (const auto &p : app->external_ports)
      if (p.name == name.port) {
        wanted.component = p.component;
        wanted.port = p.port;
      }
  auto list = client.call<connection_ops::List>({name.app}, timeout);
  if (!list)
    return tl::unexpected(Failure{exit_code_of(list.error().status), list.error().message});
  std::vector<const connection_ops::ListedConnection *> found;
  for (const auto &c : list->connections)
    if (!c.topic.empty() && (end_is(c.uses, wanted) || end_is(c.provides, wanted)))
      found.push_back(&c);
  if (found.empty())
    return tl::unexpected(Failure{
        kNotFound, fmt::format("application {} has no data connection of port {}{} (an "
                               "unconnected port carries nothing)",
                               name.app, wanted.component.empty() ? "" : wanted.component + ".",
                               wanted.port)});
  // A uses port with several connections writes the same to each: the first shows them.
  const bool one_topic = std::all_of(found.begin(), found.end(),
                                     [&](const auto *c) { return c->uses == found.front()->uses; });
  if (!one_topic) {
    std::vector<std::string> ids;
    for (const auto *c : found)
      ids.push_back(fmt::format("{} ({} -> {})", c->id, c->uses, c->provides));
    return tl::unexpected(Failure{
        kUsage, fmt::format("port {} is in several connections from different writers: {}; name "
                            "the component (APP/COMPONENT.PORT) of one",
                            wanted.port, fmt::join(ids, ", "))});
  }
  return source_of(*found.front(), *app);
}

// The viewer's DDS reader, and the tap it keeps open.
class Viewer {
public:
  static Resolved<Viewer> open(const DomainClient &client, PortSource source,
                               std::chrono::milliseconds timeout) {
    Viewer v(client, std::move(source), timeout);
    if (auto renewed = v.renew(); !renewed)
      return tl::unexpected(renewed.error());
    const auto type = port::port_type_for_repid(v.source_.repid);
    if (!type)
      return tl::unexpected(Failure{
          kRejected, fmt::format("port type {} is not one rsca can decode", v.source_.repid)});
    v.view_ = component::SampleView::of(*type);
    auto settings = dds::DdsSettings::from_environment();
    settings.trace = "none";
    auto participant = dds::Participant::create(settings);
    if (!participant)
      return tl::unexpected(Failure{kFailed, participant.error().to_string()});
    v.participant_ = *participant;
    auto qos = dds::qos_from_json(v.source_.qos);
    if (!qos)
      return tl::unexpected(Failure{kFailed, qos.error().to_string()});
    auto topic = dds::checked(dds_create_topic(v.participant_->get(), v.view_->descriptor(),
                                               v.source_.topic.c_str(), nullptr, nullptr),
                              "creating the viewer's topic");
    if (!topic)
      return tl::unexpected(Failure{kFailed, topic.error().to_string()});
    v.topic_ = std::move(*topic);
    auto reader =
        dds::checked(dds_create_reader(v.participant_->get(), v.topic_.get(), qos->get(), nullptr),
                     "creating the viewer's reader");
    if (!reader)
      return tl::unexpected(Failure{kFailed, reader.error().to_string()});
    v.reader_ = std::move(*reader);
    return v;
  }

  // The samples that came, waiting up to `most_wait` for some; the tap is renewed meanwhile.
  Resolved<std::vector<Json>> next(std::chrono::milliseconds most_wait) {
    const auto until = Clock::now() + most_wait;
    for (;;) {
      if (auto renewed = renew(); !renewed)
        return tl::unexpected(renewed.error());
      auto samples = view_->take(reader_.get(), 1024);
      if (!samples.empty() || Clock::now() >= until)
        return samples;
      // A viewer's pace: the samples wait in the reader's history meanwhile.
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }

  const PortSource &source() const { return source_; }

private:
  Viewer(const DomainClient &client, PortSource source, std::chrono::milliseconds timeout)
      : client_(&client), source_(std::move(source)), timeout_(timeout) {}

  tl::expected<void, Failure> renew() {
    if (source_.tap_node.empty() || Clock::now() < renew_at_)
      return {};
    auto reply = control::reply_of<node_ops::Tap>(
        client_
            ->call_async_at<node_ops::Tap>(
                protocol::node_address(client_->domain(), source_.tap_node),
                {source_.ring_topic, source_.repid, static_cast<std::uint32_t>(kTapLease.count())},
                timeout_)
            .get());
    if (!reply)
      return tl::unexpected(
          Failure{exit_code_of(reply.error().status),
                  fmt::format("node {}: {}", source_.tap_node, reply.error().message)});
    source_.topic = reply->tap_topic;
    renew_at_ = Clock::now() + kTapLease / 3;
    return {};
  }

  const DomainClient *client_;
  PortSource source_;
  std::chrono::milliseconds timeout_;
  Clock::time_point renew_at_{};
  std::unique_ptr<component::SampleView> view_;
  std::shared_ptr<dds::Participant> participant_;
  dds::Entity topic_;
  dds::Entity reader_;
};

Resolved<std::chrono::milliseconds> duration_option(const std::string &text, const char *option) {
  auto d = parse_duration(text);
  if (!d || d->infinite() || d->value->count() <= 0)
    return tl::unexpected(
        Failure{kUsage, fmt::format("{} {}: give a duration such as 5s or 500ms", option, text)});
  return std::chrono::duration_cast<std::chrono::milliseconds>(*d->value);
}

Resolved<Viewer> open_viewer(const DomainClient &client, const ViewOptions &options,
                             const GlobalOptions &global) {
  auto name = parse_port(options.target);
  if (!name)
    return tl::unexpected(
        Failure{kUsage, fmt::format("{}: give the port as APP/COMPONENT.PORT or APP.PORT",
                                    options.target)});
  const std::chrono::milliseconds timeout(global.timeout_ms);
  auto source = resolve(client, *name, timeout);
  if (!source)
    return tl::unexpected(source.error());
  return Viewer::open(client, std::move(*source), timeout);
}

int failed(const char *what, const Failure &failure) {
  fmt::print(stderr, "{}: {}\n", what, failure.message);
  return failure.code;
}

Failure nothing_flows(const Viewer &viewer, const std::string &wait) {
  return {kFailed, fmt::format("no sample on connection {} for {} (is its writer running?)",
                               viewer.source().connection, wait)};
}

int run_echo(const DomainClient &client, const ViewOptions &options, const GlobalOptions &global,
             std::chrono::milliseconds wait) {
  auto viewer = open_viewer(client, options, global);
  if (!viewer)
    return failed("rsca echo", viewer.error());
  for (int shown = 0; options.count == 0 || shown < options.count;) {
    auto samples = viewer->next(wait);
    if (!samples)
      return failed("rsca echo", samples.error());
    if (samples->empty())
      return failed("rsca echo", nothing_flows(*viewer, options.wait));
    for (const auto &s : *samples) {
      if (options.count > 0 && shown >= options.count)
        break;
      fmt::print("{}\n", global.json ? s.dump() : value_text(s, options.full));
      ++shown;
    }
    std::fflush(stdout); // a follower reads line by line
  }
  return kOk;
}

// One window of hz: the gaps between the writer's timestamps of the samples seen in it.
struct Rate {
  std::size_t count = 0;
  double seconds = 0;
  std::vector<double> gaps_ms;
  std::uint64_t last_ns = 0;
  void add(std::uint64_t timestamp_ns) {
    if (last_ns != 0 && timestamp_ns > last_ns)
      gaps_ms.push_back(static_cast<double>(timestamp_ns - last_ns) / 1e6);
    last_ns = timestamp_ns;
    ++count;
  }
  Json json() const {
    Json out{{"count", count}, {"window_s", seconds}, {"rate_hz", count / seconds}};
    if (!gaps_ms.empty()) {
      double sum = 0;
      for (double g : gaps_ms)
        sum += g;
      out["gap_mean_ms"] = sum / static_cast<double>(gaps_ms.size());
      out["gap_min_ms"] = *std::min_element(gaps_ms.begin(), gaps_ms.end());
      out["gap_max_ms"] = *std::max_element(gaps_ms.begin(), gaps_ms.end());
    }
    return out;
  }
};

void print_rate(const Json &r, bool json) {
  if (json)
    fmt::print("{}\n", r.dump());
  else if (r.contains("gap_mean_ms"))
    fmt::print("rate {:.2f} Hz  gap mean {:.2f} ms  min {:.2f} ms  max {:.2f} ms  count {} in "
               "{:.1f} s\n",
               r.at("rate_hz").get<double>(), r.at("gap_mean_ms").get<double>(),
               r.at("gap_min_ms").get<double>(), r.at("gap_max_ms").get<double>(),
               r.at("count").get<std::size_t>(), r.at("window_s").get<double>());
  else
    fmt::print("rate {:.2f} Hz  count {} in {:.1f} s\n", r.at("rate_hz").get<double>(),
               r.at("count").get<std::size_t>(), r.at("window_s").get<double>());
  std::fflush(stdout);
}

int run_hz(const DomainClient &client, const ViewOptions &options, const GlobalOptions &global,
           std::chrono::milliseconds wait, std::chrono::milliseconds window) {
  auto viewer = open_viewer(client, options, global);
  if (!viewer)
    return failed("rsca hz", viewer.error());
  auto last_sample = Clock::now();
  for (int windows = 0; options.count == 0 || windows < options.count; ++windows) {
    Rate rate;
    const auto began = Clock::now();
    for (auto now = began; now < began + window; now = Clock::now()) {
      auto samples = viewer->next(std::chrono::duration_cast<std::chrono::milliseconds>(
          std::min<Clock::duration>(began + window - now, std::chrono::milliseconds(100))));
      if (!samples)
        return failed("rsca hz", samples.error());
      if (!samples->empty())
        last_sample = Clock::now();
      else if (Clock::now() - last_sample > wait)
        return failed("rsca hz", nothing_flows(*viewer, options.wait));
      for (const auto &s : *samples)
        rate.add(s.value("timestamp_ns", std::uint64_t{0}));
    }
    rate.seconds = std::chrono::duration<double>(Clock::now() - began).count();
    print_rate(rate.json(), global.json);
  }
  return kOk;
}

int view(const ViewOptions &options, const GlobalOptions &global, bool hz) {
  const char *what = hz ? "rsca hz" : "rsca echo";
  auto wait = duration_option(options.wait, "--wait");
  auto window = duration_option(options.window, "-w");
  for (const auto *bad : {&wait, &window})
    if (!*bad)
      return failed(what, bad->error());
  auto client = DomainClient::connect(global);
  if (!client)
    return failed(what, {kFailed, client.error().to_string()});
  return hz ? run_hz(*client, options, global, *wait, *window)
            : run_echo(*client, options, global, *wait);
}

struct ViewCommand {
  CLI::App *cmd;
  std::shared_ptr<ViewOptions> options;
};

// rsca echo or rsca hz (`name`), with the options they share; -n counts `counted` (samples,
// windows). Its options live as long as the command's callback.
ViewCommand add_view_command(CLI::App &app, const std::string &name, const std::string &description,
                             const std::string &counted, const GlobalOptions &global,
                             int &exit_code) {
  auto options = std::make_shared<ViewOptions>();
  auto *cmd = app.add_subcommand(name, description);
  cmd->add_option("port", options->target,
                  "APP/COMPONENT.PORT, or APP.PORT (an external port, or a port one of its "
                  "components has)")
      ->required();
  cmd->add_option("--wait", options->wait,
                  "Fail (exit 6) when no sample comes for this long (default 10s)");
  cmd->add_option("-n,--count", options->count, "Stop after this many " + counted)
      ->check(CLI::PositiveNumber);
  const bool hz = name == "hz";
  cmd->callback([options, hz, &global, &exit_code] { exit_code = view(*options, global, hz); });
  return {cmd, std::move(options)};
}

} // namespace

void add_echo_commands(CLI::App &app, const GlobalOptions &global, int &exit_code) {
  const auto echo = add_view_command(
      app, "echo",
      "Print the samples a port's connection carries as they flow, without disturbing it (a "
      "lossy viewer: a slow one misses samples, the connection does not); --json: one object a "
      "line. Ctrl-C stops",
      "samples", global, exit_code);
  echo.cmd->add_flag("--full", echo.options->full, "Print long sequences whole (else summarised)");
  const auto hz = add_view_command(app, "hz",
                                   "Print the rate of a port's samples (Hz, by the writer's "
                                   "timestamps) and the mean, least and largest gap between them, "
                                   "once a window, without disturbing the connection. Ctrl-C stops",
                                   "windows", global, exit_code);
  hz.cmd->add_option("-w,--window", hz.options->window, "The window of each figure (default 5s)");
}

} // namespace rsca::cli
