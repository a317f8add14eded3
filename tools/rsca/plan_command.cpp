// rsca plan SAD|NAME: admission and placement without launching anything — against the running
// domain, or offline against node DCDs (--node), so a profile can be checked with no domain up.
#include <filesystem>

#include <fmt/format.h>

#include "allocator/plan_json.hpp"
#include "allocator/planner.hpp"
#include "commands.hpp"
#include "domain_client.hpp"
#include "exit_codes.hpp"
#include "install_code.hpp"
#include "profile/profile_loader.hpp"
#include "protocol/application_ops.hpp"

namespace rsca::cli {
namespace {

namespace fs = std::filesystem;
namespace app_ops = protocol::application;
using control::Json;

struct PlanArgs {
  std::string what;
  std::vector<std::string> nodes;
  std::vector<std::string> assignments;
  std::string strategy; // empty: the domain's (offline: pack)
};

std::string milliseconds(const Json &ns) {
  return fmt::format("{:g} ms", ns.get<double>() / 1e6);
}

std::string describe_demand(const Json &demand) {
  std::string out;
  for (const auto &[name, amount] : demand.items())
    if (amount.is_number() && amount.get<double>() > 0)
      out += fmt::format("{}{} {:g}", out.empty() ? "" : ", ", name, amount.get<double>());
  return out.empty() ? "no declared demand" : out;
}

void print_plan(const std::string &application, const app_ops::PlanReply &result) {
  fmt::print("plan for {} (strategy {}): {}\n", application, result.strategy,
             result.admitted ? "admitted" : "rejected");
  if (!result.admitted) {
    for (const auto &r : result.rejections.value_or(Json::array())) {
      fmt::print("  {}: cannot be placed\n", r.value("component", ""));
      for (const auto &reason : r.at("reasons"))
        fmt::print("    {}\n", reason.get<std::string>());
    }
    return;
  }
  const Json plan = result.plan.value_or(Json::object());
  for (const auto &p : plan.at("placements")) {
    fmt::print("  {:<20} -> {:<16} ({})  {}\n", p.value("component", ""), p.value("device", ""),
               p.value("implementation", ""), describe_demand(p.at("demand")));
    if (p.contains("schedule")) {
      const auto &s = p.at("schedule");
      fmt::print("  {:<20}    cpu {} {}, priority {}, period {}, budget {}, worst response {}\n",
                 "", s.value("cpu", 0), s.value("policy", ""), s.value("priority", 0),
                 milliseconds(s.at("period_ns")), milliseconds(s.at("budget_ns")),
                 milliseconds(s.at("response_time_ns")));
    }
    for (const auto &u : p.at("uses_devices"))
      fmt::print("  {:<20}    uses {} ({})\n", "", u.value("device", ""),
                 u.value("usesdevice", ""));
  }
  for (const auto &u : plan.at("uses_devices"))
    fmt::print("  application uses {} ({})\n", u.value("device", ""), u.value("usesdevice", ""));
  for (const auto &note : plan.at("notes"))
    fmt::print("  note: {}\n", note.get<std::string>());
}

int report(const std::string &application, const app_ops::PlanReply &result,
           const GlobalOptions &global) {
  if (global.json)
    print_json(protocol::encode(result));
  else
    print_plan(application, result);
  return result.admitted ? kOk : kRejected;
}

// Offline: the devices the DCDs declare, valued from their PRFs and the DCDs alone.
Expected<allocator::DomainState> offline_domain(const std::vector<std::string> &dcds) {
  allocator::DomainState state;
  for (const auto &dcd : dcds) {
    profile::ProfileLoader loader; // each DCD's SDR root is found from where it lies
    auto node = loader.load_node(dcd);
    if (!node)
      return tl::unexpected(node.error());
    for (auto &device : allocator::devices_of_node(*node)) {
      const std::string id = device.id;
      state.emplace(id, allocator::DeviceState{std::move(device), {}});
    }
  }
  return state;
}

int plan_offline(const PlanArgs &args, const std::map<std::string, std::string> &assign,
                 const GlobalOptions &global) {
  auto application = user_profile_loader(global).load_application(args.what);
  if (!application) {
    return fail(global, "plan", kInvalidProfile, application.error().to_string());
  }
  // The domain's plan refuses it too; offline, an assignment of no component went unnoticed.
  if (auto stray = stray_assignment(*application, assign)) {
    return fail(global, "plan", kUsage, *stray);
  }
  auto domain = offline_domain(args.nodes);
  if (!domain) {
    return fail(global, "plan", kInvalidProfile, domain.error().to_string());
  }
  const allocator::PlanOptions options{
      allocator::parse_strategy(args.strategy).value_or(allocator::Strategy::Pack)};
  auto plan =
      allocator::make_plan(*domain, allocator::plan_request_of(*application, assign), options);
  return report(application->sad->name, allocator::plan_reply(plan, options.strategy), global);
}

// A SAD file is planned from its files, which the domain reads aside and removes: a dry run that
// installs nothing. An installed name is planned as installed.
int plan_online(const PlanArgs &args, const std::map<std::string, std::string> &assign,
                const GlobalOptions &global) {
  std::optional<UserApplication> files;
  if (fs::is_regular_file(args.what)) {
    auto app = read_user_application(args.what, global, "");
    if (!app) {
      return fail(global, "plan", kInvalidProfile, app.error().to_string());
    }
    files = std::move(*app);
    if (!global.json)
      for (const auto &w : files->warnings)
        fmt::print(stderr, "rsca plan: {}\n", to_string(w));
  }
  auto client = DomainClient::connect(global);
  if (!client) {
    return fail(global, "plan", kFailed, client.error().to_string());
  }
  const std::optional<std::string> strategy =
      args.strategy.empty() ? std::nullopt : std::optional(args.strategy);
  const auto timeout = std::chrono::milliseconds(global.timeout_ms);
  if (!files) {
    auto reply = client->call<app_ops::Plan>({args.what, assign, strategy}, timeout);
    if (!reply)
      return report_failure(global, "plan", reply.error());
    return report(args.what, *reply, global);
  }
  // Twice the timeout, as an install: the domain writes and reads the files first.
  auto reply = client->call<app_ops::PlanFiles>({files->request, assign, strategy}, timeout * 2);
  if (!reply)
    return report_failure(global, "plan", reply.error());
  const auto &sad = *files->profile.sad;
  return report(sad.name.empty() ? sad.id : sad.name, *reply, global);
}

} // namespace

void add_plan_command(CLI::App &app, const GlobalOptions &global, int &exit_code) {
  auto *cmd = app.add_subcommand(
      "plan", "Admission and placement of an application without launching it: against the "
              "running domain, or offline against node DCDs (--node)");
  auto args = std::make_shared<PlanArgs>();
  cmd->add_option("application", args->what, "SAD file or installed application name")->required();
  cmd->add_option("--node", args->nodes, "Plan offline against this node's DCD (repeatable)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--assign", args->assignments,
                  "Place a component on a device: COMPONENT=DEVICE (repeatable)");
  cmd->add_option("--strategy", args->strategy,
                  "Placement: pack or spread (default: the domain's; offline: pack)")
      ->check(CLI::IsMember({"pack", "spread"}));
  cmd->callback([args, &global, &exit_code] {
    auto assign = assignments_of(args->assignments, "plan");
    if (!assign) {
      exit_code = kUsage;
      return;
    }
    exit_code = args->nodes.empty() ? plan_online(*args, *assign, global)
                                    : plan_offline(*args, *assign, global);
  });
}

} // namespace rsca::cli
