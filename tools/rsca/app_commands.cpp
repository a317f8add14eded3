// rsca install | uninstall | launch | start | stop | release | configure | query, and show APP.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "commands.hpp"
#include "common/names.hpp"
#include "domain_client.hpp"
#include "exit_codes.hpp"
#include "install_code.hpp"
#include "protocol/application_ops.hpp"
#include "protocol/connection_ops.hpp"
#include "protocol/domain_ops.hpp"
#include "value_text.hpp"

namespace rsca::cli {
namespace {

namespace fs = std::filesystem;
namespace app_ops = protocol::application;
namespace connection_ops = protocol::connection;
using control::Json;
using namespace std::chrono_literals;

// Sends the install of the user's application; its installed name goes to `installed_name` (and
// nothing is printed in --json mode) when given. `command`: the one the user ran.
int send_install(const UserApplication &app, const DomainClient &client,
                 const GlobalOptions &global, std::string *installed_name, const char *command) {
  if (!global.json)
    for (const auto &w : app.warnings)
      fmt::print(stderr, "rsca {}: {}\n", command, to_string(w));
  auto reply = client.call<protocol::domain::Install>(
      app.request, std::chrono::milliseconds(global.timeout_ms) * 2);
  if (!reply)
    return report_failure(global, command, reply.error());
  if (installed_name != nullptr)
    *installed_name = reply->name;
  if (global.json && installed_name == nullptr)
    print_json(protocol::encode(*reply));
  else if (!global.json)
    fmt::print("installed {} ({} files)\n", reply->name, app.request.files.size());
  return kOk;
}

// What a launch launches: an installed name, or a SAD file installed first for it (the domain
// keeps that install only if the launch succeeds: CreateRequest::settles_install). rc: an exit
// code.
struct LaunchTarget {
  std::string application;
  bool installed_for_it = false;
};

LaunchTarget install_to_launch(const UserApplication &app, const DomainClient &client,
                               const GlobalOptions &global, int &rc) {
  LaunchTarget target;
  rc = send_install(app, client, global, &target.application, "launch");
  target.installed_for_it = rc == kOk;
  return target;
}

} // namespace

int install(const std::string &sad, const std::string &name, const GlobalOptions &global,
            std::string *installed_name) {
  if (!name.empty())
    if (auto named = check_name("--name", name); !named) {
      return fail(global, "install", kUsage, named.error().diagnostics().front().message);
    }
  auto app = read_user_application(sad, global, name);
  if (!app) {
    return fail(global, "install", kInvalidProfile, app.error().to_string());
  }
  auto client = DomainClient::connect(global);
  if (!client) {
    return fail(global, "install", kFailed, client.error().to_string());
  }
  return send_install(*app, *client, global, installed_name, "install");
}

std::optional<std::map<std::string, std::string>>
assignments_of(const std::vector<std::string> &assignments, const char *command) {
  std::map<std::string, std::string> assign;
  for (const auto &a : assignments) {
    auto eq = a.find('=');
    if (eq == std::string::npos || eq == 0) {
      fmt::print(stderr, "rsca {}: --assign takes COMPONENT=DEVICE, not \"{}\"\n", command, a);
      return std::nullopt;
    }
    assign[a.substr(0, eq)] = a.substr(eq + 1);
  }
  return assign;
}

namespace {

std::atomic<bool> g_interrupted{false};

// Ctrl-C during a launch: noted, so that the launch is cancelled rather than the CLI killed.
class InterruptsNoted {
public:
  InterruptsNoted() {
    g_interrupted = false;
    struct sigaction noting {};
    noting.sa_handler = [](int) { g_interrupted = true; };
    sigemptyset(&noting.sa_mask);
    sigaction(SIGINT, &noting, &previous_);
  }
  ~InterruptsNoted() { sigaction(SIGINT, &previous_, nullptr); }
  InterruptsNoted(const InterruptsNoted &) = delete;
  InterruptsNoted &operator=(const InterruptsNoted &) = delete;

private:
  struct sigaction previous_ {};
};

// What of a launch's progress the terminal has shown.
struct Shown {
  std::size_t steps = 0;
  std::uint64_t delivered_bytes = 0; // files the nodes fetched, as last shown
};

// Prints the launch steps the domain completed since the last call, and the files its nodes
// fetched while a step (execute) is under way, each megabyte more.
void print_progress(const DomainClient &client, const std::string &launch_id, Shown &shown) {
  auto progress = client.call<app_ops::Progress>({launch_id}, 2s);
  if (!progress)
    return;
  const auto delivered = progress->delivered_bytes.value_or(0);
  if (!progress->done && delivered >= shown.delivered_bytes + 1'000'000) {
    fmt::print("  ~ {:<10} {:>8.1f} MB of files delivered to the nodes so far ({:.1f} MB on the "
               "wire)\n",
               "execute", static_cast<double>(delivered) / 1e6,
               static_cast<double>(progress->delivered_wire_bytes.value_or(delivered)) / 1e6);
    shown.delivered_bytes = delivered;
  }
  const auto &steps = progress->steps;
  for (; shown.steps < steps.size(); ++shown.steps) {
    const auto &s = steps[shown.steps];
    const bool failed = s.detail == "failed";
    fmt::print("  {} {:<10} {:>8.1f} ms  {}\n", failed ? "x" : "+", s.step, s.ms,
               failed ? "" : s.detail);
  }
}

// Asks the domain to cancel a launch the CLI stops waiting for (its deadline passed, or Ctrl-C),
// so that no application the user was told had not launched turns up later; says what became of
// it.
std::string cancel_launch(const DomainClient &client, const std::string &launch_id,
                          const GlobalOptions &global) {
  // At least 2 s: a user who wants quick answers (a small --timeout-ms) still wants it cancelled.
  const auto timeout =
      std::max<std::chrono::milliseconds>(std::chrono::milliseconds(global.timeout_ms), 2s);
  auto cancelled = client.call<app_ops::Cancel>({launch_id}, timeout);
  if (!cancelled)
    return fmt::format("cancelling it failed ({}): it may still be under way (see `rsca ls apps`)",
                       cancelled.error().message);
  if (!cancelled->cancelled)
    return "it finished meanwhile (see `rsca ls apps`)";
  if (!cancelled->begun.value_or(true))
    return "the launch is cancelled before it began: the domain will not start it";
  return "the launch is cancelled: the domain rolls back what it did (see `rsca ls apps`)";
}

// Waits for the launch's reply, showing its steps on a terminal. On Ctrl-C it asks the domain
// once to cancel the launch and goes on waiting: the reply then says what was rolled back.
control::CallResult<app_ops::CreateReply>
await_launch(const DomainClient &client, const std::string &launch_id,
             std::future<control::CallResult<Json>> &launch, bool show_progress,
             const GlobalOptions &global) {
  Shown shown;
  bool cancelling = false;
  for (;;) {
    const bool finished = launch.wait_for(50ms) == std::future_status::ready;
    if (show_progress)
      print_progress(client, launch_id, shown);
    if (finished)
      return control::reply_of<app_ops::Create>(launch.get());
    if (g_interrupted && !cancelling) {
      cancelling = true;
      const std::string outcome = cancel_launch(client, launch_id, global);
      if (!global.json)
        fmt::print(stderr, "rsca launch: interrupted; {}\n", outcome);
    }
  }
}

int launch(const std::string &what, const std::string &name, bool no_start,
           const std::vector<std::string> &assignments, const std::string &strategy,
           const GlobalOptions &global) {
  auto assign = assignments_of(assignments, "launch");
  if (!assign)
    return kUsage;
  int rc = kOk;
  std::optional<UserApplication> file;
  if (fs::is_regular_file(what))
    if (file = launchable_file(what, *assign, global, rc); !file)
      return rc;
  auto client = DomainClient::connect(global);
  if (!client) {
    return fail(global, "launch", kFailed, client.error().to_string());
  }
  LaunchTarget target{what, false};
  if (file)
    if (target = install_to_launch(*file, *client, global, rc); rc != kOk)
      return rc;
  const std::string &application = target.application;
  const std::string launch_id =
      fmt::format("{}-{}", getpid(), std::chrono::steady_clock::now().time_since_epoch().count());
  app_ops::CreateRequest request;
  request.application = application;
  request.start = !no_start;
  request.assign = *assign;
  request.launch_id = launch_id;
  if (target.installed_for_it)
    request.settles_install = true;
  if (!strategy.empty())
    request.strategy = strategy;
  if (!name.empty())
    request.name = name;
  const bool show_progress = !global.json && isatty(STDOUT_FILENO);
  if (show_progress)
    fmt::print("launching {}\n", application);
  const auto launch_timeout = std::chrono::milliseconds(global.timeout_ms) * 6;
  const auto sent = std::chrono::steady_clock::now();
  InterruptsNoted interrupts;
  auto future = client->call_async<app_ops::Create>(request, launch_timeout);
  auto reply = await_launch(*client, launch_id, future, show_progress, global);
  const bool timed_out = !reply && reply.error().status == control::Status::Timeout &&
                         std::chrono::steady_clock::now() - sent >= launch_timeout;
  if (!reply && file)
    reply.error().message = as_user_paths(reply.error().message, application, *file);
  // The CLI's own deadline, not the domain's reply that a step timed out: the domain took the
  // request (else the call fails as unavailable) but is not done with it.
  if (timed_out) {
    return report_failure(global, "launch",
                          {control::Status::Timeout,
                           fmt::format("the domain had not finished launching {} after {} ms; {}; "
                                       "a larger --timeout-ms waits longer (six times it for a "
                                       "launch)",
                                       application, launch_timeout.count(),
                                       cancel_launch(*client, launch_id, global))});
  }
  if (!reply && reply.error().maybe_received) {
    auto error = reply.error();
    error.message += "; the launch may still be under way, or what it started may still run "
                     "(`rsca ls apps` says; a domain daemon started again reports it)";
    return report_failure(global, "launch", error);
  }
  if (!reply)
    return report_failure(global, "launch", reply.error());
  if (global.json) {
    print_json(protocol::encode(*reply));
    return kOk;
  }
  fmt::print("{} {} ({} components)\n", no_start ? "created" : "launched", reply->name,
             reply->components.size());
  return kOk;
}

// A call of `Op` by a command that waits twice the timeout (the domain calls components in turn).
template <control::Operation Op>
int simple_call(const std::string &what, const typename Op::Request &request,
                const GlobalOptions &global,
                const std::function<void(const typename Op::Reply &)> &print_text) {
  return call_and_print<Op>(global, what, request, std::chrono::milliseconds(global.timeout_ms) * 2,
                            print_text);
}

// APP, APP/COMPONENT or NODE:DEVICE, into the request's target.
void set_target(const std::string &target, app_ops::Target &request) {
  if (target.find(':') != std::string::npos) {
    request.device = target;
    return;
  }
  const auto slash = target.find('/');
  request.app = target.substr(0, slash);
  request.component = slash == std::string::npos ? "" : target.substr(slash + 1);
}

// APP/COMPONENT.PORT (a component's port), NODE:DEVICE.PORT (a device's) or APP.PORT (an
// application's external port).
std::optional<connection_ops::PortEnd> port_end(const std::string &text) {
  const auto dot = text.rfind('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == text.size())
    return std::nullopt;
  const std::string owner = text.substr(0, dot), port = text.substr(dot + 1);
  connection_ops::PortEnd end{std::nullopt, std::nullopt, std::nullopt, port};
  if (const auto slash = owner.find('/'); slash != std::string::npos) {
    if (slash == 0 || slash + 1 == owner.size())
      return std::nullopt;
    end.application = owner.substr(0, slash);
    end.component = owner.substr(slash + 1);
  } else if (owner.find(':') != std::string::npos) {
    end.device = owner;
  } else {
    end.application = owner;
  }
  return end;
}

using TextValues = std::map<std::string, std::string>;

// QoS values given as text: numbers (depth, strength, ...) as numbers, the rest as text.
Json typed_qos(const TextValues &values) {
  Json out = Json::object();
  for (const auto &[k, text] : values) {
    const bool number = !text.empty() && text.find_first_not_of("0123456789") == std::string::npos;
    out[k] = number ? Json(std::stoll(text)) : Json(text);
  }
  return out;
}

// prop=value arguments; values are sent as text and typed by the domain against the PRF.
std::optional<TextValues> parse_assignments(const std::vector<std::string> &args) {
  TextValues values;
  for (const auto &a : args) {
    auto eq = a.find('=');
    if (eq == std::string::npos || eq == 0)
      return std::nullopt;
    values[a.substr(0, eq)] = a.substr(eq + 1);
  }
  return values;
}

} // namespace

// rsca channel create|destroy NAME.
template <control::Operation Op>
void add_channel_command(CLI::App &channel_cmd, const char *verb, const char *done,
                         const GlobalOptions &global, int &exit_code) {
  auto *cmd = channel_cmd.add_subcommand(verb, std::string(verb) + " an event channel");
  auto channel = std::make_shared<std::string>();
  cmd->add_option("name", *channel, "The channel's name")->required();
  cmd->callback([=, &global, &exit_code] {
    exit_code = simple_call<Op>(
        fmt::format("channel {}", verb), {*channel}, global,
        [done](const typename Op::Reply &r) { fmt::print("channel {}: {}\n", done, r.name); });
  });
}

// rsca start|stop|release APP: `print_text` prints the reply.
template <control::Operation Op>
void add_lifecycle_command(CLI::App &app, const char *verb, const char *help,
                           const GlobalOptions &global, int &exit_code,
                           std::function<void(const typename Op::Reply &)> print_text) {
  auto *cmd = app.add_subcommand(verb, help);
  auto target = std::make_shared<std::string>();
  cmd->add_option("app", *target, "Running application")->required();
  cmd->callback([=, &global, &exit_code] {
    exit_code = simple_call<Op>(verb, {*target}, global, print_text);
  });
}

void add_lifecycle_commands(CLI::App &app, const GlobalOptions &global, int &exit_code) {
  const auto print_name = [](const char *verb) {
    return [verb](const app_ops::ApplicationView &r) { fmt::print("{}: {}\n", verb, r.name); };
  };
  add_lifecycle_command<app_ops::Start>(app, "start", "Start a created or stopped application",
                                        global, exit_code, print_name("start"));
  add_lifecycle_command<app_ops::Stop>(app, "stop", "Stop a running application", global, exit_code,
                                       print_name("stop"));
  add_lifecycle_command<app_ops::Release>(
      app, "release", "Tear an application down: its processes, connections and allocations",
      global, exit_code, [](const app_ops::ReleaseReply &r) {
        fmt::print("release: {}\n", r.name);
        for (const auto &id : r.unconfirmed)
          fmt::print("  {} did not confirm its release and was terminated by its node\n", id);
        for (const auto &lost : r.to_end_later.value_or(std::vector<app_ops::LostComponent>{}))
          fmt::print("  {} could not be ended: its node {} is lost; to be ended when its node {} "
                     "is back\n",
                     lost.component, lost.node, lost.node);
      });
}
int show_application(const std::string &name, const GlobalOptions &global) {
  return simple_call<app_ops::Show>(
      "show", {name}, global, [](const app_ops::ApplicationView &app) {
        fmt::print("application {} ({}) {}{}\n", app.name, app.installed, app.state,
                   app.exited.empty() ? ""
                                      : fmt::format(": exited {}", fmt::join(app.exited, ", ")));
        fmt::print("  components:\n");
        for (const auto &c : app.components)
          fmt::print("    {:<20} {:<16} pid {:<8} {}{}\n", c.id, c.device, c.pid,
                     protocol::enum_name(c.state),
                     c.assembly_controller ? "  (assembly controller)" : "");
        if (!app.connections.empty())
          fmt::print("  connections:\n");
        for (const auto &c : app.connections)
          fmt::print("    {:<16} {} -> {}  [{}]{}\n", c.id, c.uses, c.provides, c.topic,
                     c.state ? fmt::format(" {}", protocol::enum_name(*c.state)) : "");
      });
}

namespace {

// What a configure set, each as `set ID (COMPONENT:PROPERTY) = VALUE`.
void print_configured(const app_ops::ConfigureReply &reply) {
  for (const auto &one : reply.set)
    fmt::print("set {} ({}{}) = {}\n", one.id, one.component.empty() ? "" : one.component + ":",
               one.property,
               one.value.is_string() ? one.value.get<std::string>() : one.value.dump());
}

// rsca configure TARGET [COMPONENT] property=value...
void add_configure_command(CLI::App &app, const GlobalOptions &global, int &exit_code) {
  auto *cmd = app.add_subcommand(
      "configure",
      "Set properties of an application (its external properties, else its assembly "
      "controller's), of one component (APP/COMPONENT or APP COMPONENT), or of a device "
      "(NODE:DEVICE). Values: a simple as it is (rate=10); a sequence as [1,2,3] or 1,2,3; a "
      "struct as {member=value,member2=[1,2]}; a sequence of structs as [{a=1},{a=2}]; quote an "
      "item holding , [ ] { } = as \"...\"; or any value as JSON after json: (s=json:{\"a\":1}). "
      "Prints what it set: ID (COMPONENT:PROPERTY) = VALUE");
  auto target = std::make_shared<std::string>();
  auto args = std::make_shared<std::vector<std::string>>();
  cmd->add_option("target", *target, "APP, APP/COMPONENT or NODE:DEVICE")->required();
  cmd->add_option("values", *args, "[COMPONENT] property=value ...")->required();
  cmd->callback([=, &global, &exit_code] {
    std::string where = *target;
    std::vector<std::string> assignments = *args;
    // APP COMPONENT prop=value: the component as its own word, as APP/COMPONENT.
    const bool component_word = where.find_first_of("/:") == std::string::npos &&
                                assignments.size() > 1 &&
                                assignments.front().find('=') == std::string::npos;
    if (component_word) {
      where += "/" + assignments.front();
      assignments.erase(assignments.begin());
    }
    auto values = parse_assignments(assignments);
    if (!values) {
      fmt::print(stderr, "rsca configure: give properties as property=value (rsca configure "
                         "--help says how to write sequences and structs)\n");
      exit_code = kUsage;
      return;
    }
    app_ops::ConfigureRequest request;
    set_target(where, request);
    request.values.emplace(values->begin(), values->end());
    exit_code = simple_call<app_ops::Configure>("configure", request, global, print_configured);
  });
}

} // namespace

void add_application_commands(CLI::App &app, const GlobalOptions &global, int &exit_code) {
  auto *install_cmd = app.add_subcommand(
      "install", "Install an application (its SAD and every profile it names) in the domain");
  auto sad = std::make_shared<std::string>();
  auto name = std::make_shared<std::string>();
  install_cmd->add_option("sad", *sad, "The application's SAD")
      ->required()
      ->check(CLI::ExistingFile);
  install_cmd->add_option("--name", *name, "Install under this name (default: the SAD's name)");
  install_cmd->callback([=, &global, &exit_code] { exit_code = install(*sad, *name, global); });

  auto *uninstall_cmd = app.add_subcommand("uninstall", "Remove an installed application");
  auto installed = std::make_shared<std::string>();
  uninstall_cmd->add_option("name", *installed, "Installed application")->required();
  uninstall_cmd->callback([=, &global, &exit_code] {
    exit_code = simple_call<protocol::domain::Uninstall>(
        "uninstall", {*installed}, global,
        [](const protocol::domain::Named &r) { fmt::print("uninstalled {}\n", r.name); });
  });

  auto *launch_cmd = app.add_subcommand(
      "launch", "Create (and start) an application from a SAD or an installed name");
  auto what = std::make_shared<std::string>();
  auto instance = std::make_shared<std::string>();
  auto no_start = std::make_shared<bool>(false);
  auto assign = std::make_shared<std::vector<std::string>>();
  launch_cmd->add_option("application", *what, "SAD file or installed application name")
      ->required();
  launch_cmd->add_option("--name", *instance, "Name of the running application");
  launch_cmd->add_flag("--no-start", *no_start, "Create and connect, but do not start");
  launch_cmd->add_option("--assign", *assign,
                         "Place a component on a device: COMPONENT=DEVICE (repeatable)");
  auto strategy = std::make_shared<std::string>();
  launch_cmd
      ->add_option("--strategy", *strategy, "Placement: pack or spread (default: the domain's)")
      ->check(CLI::IsMember({"pack", "spread"}));
  launch_cmd->callback([=, &global, &exit_code] {
    exit_code = launch(*what, *instance, *no_start, *assign, *strategy, global);
  });

  auto *connect_cmd = app.add_subcommand(
      "connect",
      "Connect a uses port to a provides port: APP/COMPONENT.PORT, APP.PORT (an external port) "
      "or NODE:DEVICE.PORT. An end not there yet (an application not launched, a device not "
      "registered) makes the connection pending until it appears; it lasts until disconnected");
  auto uses_end = std::make_shared<std::string>();
  auto provides_end = std::make_shared<std::string>();
  auto connection_id = std::make_shared<std::string>();
  auto qos_args = std::make_shared<std::vector<std::string>>();
  connect_cmd->add_option("uses", *uses_end, "The uses port")->required();
  connect_cmd->add_option("provides", *provides_end, "The provides port")->required();
  connect_cmd->add_option("--id", *connection_id, "The connection's id (default: runtime_N)");
  connect_cmd->add_option("--qos", *qos_args, "QoS as in the SAD: name=value (repeatable)");
  auto filter = std::make_shared<std::string>();
  connect_cmd->add_option("--filter", *filter,
                          "A content filter for the provides end, as a SAD's <filter>");
  connect_cmd->callback([=, &global, &exit_code] {
    auto uses = port_end(*uses_end);
    auto provides = port_end(*provides_end);
    auto qos = parse_assignments(*qos_args);
    if (!uses || !provides || !qos) {
      fmt::print(stderr, "rsca connect: give ports as APP/COMPONENT.PORT, APP.PORT or "
                         "NODE:DEVICE.PORT, and QoS as name=value\n");
      exit_code = kUsage;
      return;
    }
    connection_ops::CreateRequest request{*uses, *provides, std::nullopt, typed_qos(*qos),
                                          std::nullopt};
    if (!connection_id->empty())
      request.id = *connection_id;
    if (!filter->empty())
      request.filter = *filter;
    exit_code = simple_call<connection_ops::Create>(
        "connect", request, global, [](const connection_ops::CreateReply &r) {
          if (r.state == connection_ops::ConnectionState::Pending)
            fmt::print("pending {}: {} -> {} (waiting: {})\n", r.id, r.uses, r.provides,
                       r.waiting_for.value_or(""));
          else
            fmt::print("connected {}: {} -> {} [{}]\n", r.id, r.uses, r.provides, r.topic);
        });
  });
  auto *disconnect_cmd =
      app.add_subcommand("disconnect", "Remove a connection made with rsca connect");
  auto disconnect_id = std::make_shared<std::string>();
  disconnect_cmd->add_option("id", *disconnect_id, "The connection's id")->required();
  disconnect_cmd->callback([=, &global, &exit_code] {
    exit_code = simple_call<connection_ops::Destroy>(
        "disconnect", {*disconnect_id}, global,
        [](const connection_ops::ConnectionId &r) { fmt::print("disconnected {}\n", r.id); });
  });

  auto *channel_cmd = app.add_subcommand(
      "channel", "Create or destroy an operator's event channel (it lives until destroyed)");
  channel_cmd->require_subcommand(1);
  add_channel_command<connection_ops::CreateChannel>(*channel_cmd, "create", "created", global,
                                                     exit_code);
  add_channel_command<connection_ops::DestroyChannel>(*channel_cmd, "destroy", "destroyed", global,
                                                      exit_code);
  add_lifecycle_commands(app, global, exit_code);

  add_configure_command(app, global, exit_code);

  auto *query_cmd = app.add_subcommand(
      "query", "Read properties of an application's assembly controller, one component, or a "
               "device (NODE:DEVICE)");
  auto query_target = std::make_shared<std::string>();
  auto ids = std::make_shared<std::vector<std::string>>();
  query_cmd->add_option("target", *query_target, "APP, APP/COMPONENT or NODE:DEVICE")->required();
  query_cmd->add_option("properties", *ids, "Property ids (default: all)");
  auto full = std::make_shared<bool>(false);
  query_cmd->add_flag("--full", *full,
                      "Print long values whole (a sequence of more than 8 values, text of more "
                      "than 200 characters is otherwise summarised; --json prints them whole)");
  query_cmd->callback([=, &global, &exit_code] {
    app_ops::QueryRequest request;
    set_target(*query_target, request);
    request.ids = *ids;
    exit_code = simple_call<app_ops::Query>(
        "query", request, global, [full](const protocol::component::QueryReply &r) {
          for (const auto &[id, value] : r.properties.items())
            fmt::print("{} = {}\n", id, value_text(value, *full));
        });
  });
}

} // namespace rsca::cli
