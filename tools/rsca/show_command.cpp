// rsca show PATH: the resolved model of one profile as a readable tree.
#include <algorithm>
#include <filesystem>
#include <iostream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "domain_client.hpp"
#include "exit_codes.hpp"
#include "profile/profile_loader.hpp"
#include "profile/property_binding.hpp"

namespace rsca::cli {
namespace {

namespace fs = std::filesystem;
using namespace rsca::profile;

template <class... Ts>
struct Overloaded : Ts... {
  using Ts::operator()...;
};
template <class... Ts>
Overloaded(Ts...) -> Overloaded<Ts...>;

// Writes indented lines, and keeps them for --json.
class Tree {
public:
  void line(int depth, const std::string &text) {
    out_ += std::string(static_cast<std::size_t>(depth) * 2, ' ') + text + '\n';
    lines_.emplace_back(static_cast<std::size_t>(std::max(depth, 0)), text);
  }
  const std::string &str() const { return out_; }
  // The lines nested as they are indented: [{"text": ..., "children": [...]}, ...].
  nlohmann::json json() const {
    nlohmann::json root = nlohmann::json::array();
    std::vector<nlohmann::json *> open{&root}; // open[d]: where a line of depth d goes
    for (const auto &[depth, text] : lines_) {
      open.resize(std::min(depth, open.size() - 1) + 1);
      auto &node = open.back()->emplace_back(
          nlohmann::json{{"text", text}, {"children", nlohmann::json::array()}});
      open.push_back(&node["children"]);
    }
    return root;
  }

private:
  std::string out_;
  std::vector<std::pair<std::size_t, std::string>> lines_;
};

std::string type_name(TypeSpec spec) {
  return spec.complex ? fmt::format("complex {}", to_string(spec.type))
                      : std::string(to_string(spec.type));
}

std::string kinds_of(const PropertyCommon &p) {
  std::vector<std::string_view> kinds;
  for (auto k : p.kinds)
    kinds.push_back(to_string(k));
  if (kinds.empty())
    kinds.push_back("configure");
  return fmt::format("{}", fmt::join(kinds, ","));
}

std::string describe(const PropertyDefinition &d) {
  const PropertyCommon &c = common_of(d);
  std::string head = c.id == c.label() ? c.id : fmt::format("{} ({})", c.label(), c.id);
  std::string form = std::visit(
      Overloaded{
          [](const SimpleProperty &p) {
            std::string s = type_name(p.type);
            if (!p.units.empty())
              s += fmt::format(" [{}]", p.units);
            if (p.action)
              s += fmt::format(" action={}", to_string(*p.action));
            return s;
          },
          [](const SimpleSequenceProperty &p) { return "sequence of " + type_name(p.type); },
          [](const StructProperty &p) { return fmt::format("struct of {}", p.members.size()); },
          [](const StructSequenceProperty &p) {
            return fmt::format("sequence of struct of {}", p.element.members.size());
          }},
      d);
  std::string text = fmt::format("{}: {} {} {}", head, form, to_string(c.mode), kinds_of(c));
  if (auto value = default_value(d))
    text += " = " + format_value(*value);
  return text;
}

void show_properties(Tree &t, int depth, const Properties &prf) {
  for (const auto &p : prf.properties)
    t.line(depth, describe(p));
}

void show_ports(Tree &t, int depth, const SoftwareComponent &scd) {
  for (const auto &p : scd.ports)
    t.line(depth,
           fmt::format("{} {} : {}", p.direction == PortDirection::Uses ? "uses    " : "provides",
                       p.name, p.repid));
}

std::string describe(const ResourceDemand &d) {
  std::vector<std::string> parts;
  if (d.utilization)
    parts.push_back(fmt::format("cpu {:g}", *d.utilization));
  if (d.execution_time && d.period)
    parts.push_back(fmt::format("cpu {} per {}", format_duration(*d.execution_time),
                                format_duration(*d.period)));
  if (d.memory_bytes)
    parts.push_back("memory " + format_size(*d.memory_bytes));
  if (d.bandwidth_bps)
    parts.push_back("network " + format_bitrate(*d.bandwidth_bps));
  return fmt::format("{}", fmt::join(parts, ", "));
}

void show_softpkg(Tree &t, int depth, const ResolvedSoftPkg &pkg) {
  const SoftPkg &spd = *pkg.spd;
  t.line(depth, fmt::format("softpkg {} {} ({})", spd.name, spd.version, pkg.spd_path.string()));
  for (const auto &ri : pkg.implementations) {
    const Implementation &impl = *ri.implementation;
    std::vector<std::string> os;
    for (const auto &o : impl.os)
      os.push_back(o.name);
    t.line(depth + 1, fmt::format("implementation {}: {} {} [os {}; processor {}]", impl.id,
                                  to_string(impl.code.type), impl.code.file.name,
                                  fmt::join(os, "|"), fmt::join(impl.processors, "|")));
    if (impl.resource_demand)
      t.line(depth + 2, "demand: " + describe(*impl.resource_demand));
    for (const auto &dep : ri.dependencies)
      t.line(depth + 2, fmt::format("depends on {}{}", dep.softpkg->spd->name,
                                    dep.implref ? " (" + *dep.implref + ")" : ""));
  }
  if (pkg.scd) {
    t.line(depth + 1, "ports:");
    show_ports(t, depth + 2, *pkg.scd);
  }
  if (pkg.properties) {
    t.line(depth + 1, "properties:");
    show_properties(t, depth + 2, *pkg.properties);
  }
}

std::string describe(const EndpointTarget &target, const std::string &port) {
  switch (target.kind) {
  case EndpointTarget::Kind::FindBy:
    return fmt::format("{} \"{}\"", target.findby.is_event_channel() ? "event channel" : "findby",
                       target.findby.name);
  case EndpointTarget::Kind::DeviceThatLoadedThisComponent:
    return fmt::format("device-that-loaded({}).{}", target.refid, port);
  case EndpointTarget::Kind::DeviceUsedByThisComponent:
    return fmt::format("device-used-by({}, {}).{}", target.refid, target.usesrefid, port);
  case EndpointTarget::Kind::DeviceUsedByApplication:
    return fmt::format("device-used-by-application({}).{}", target.usesrefid, port);
  case EndpointTarget::Kind::ComponentInstantiation:
    break;
  }
  return fmt::format("{}.{}", target.refid, port);
}

std::string describe(const ConnectionQos &q) {
  std::vector<std::string> parts;
  if (q.reliability)
    parts.emplace_back(to_string(*q.reliability));
  if (q.durability)
    parts.emplace_back(to_string(*q.durability));
  if (q.history)
    parts.push_back(
        fmt::format("{}{}", to_string(*q.history), q.depth ? fmt::format("({})", *q.depth) : ""));
  if (q.deadline)
    parts.push_back("deadline " + format_duration(*q.deadline));
  if (q.latency_budget)
    parts.push_back("latency budget " + format_duration(*q.latency_budget));
  if (q.transport_priority)
    parts.push_back(fmt::format("priority {}", *q.transport_priority));
  if (q.liveliness)
    parts.push_back(fmt::format("liveliness {}", to_string(*q.liveliness)));
  if (q.lease)
    parts.push_back("lease " + format_duration(*q.lease));
  if (q.ownership)
    parts.push_back(fmt::format("{} ownership{}", to_string(*q.ownership),
                                q.strength ? fmt::format(" strength {}", *q.strength) : ""));
  return fmt::format("{}", fmt::join(parts, ", "));
}

std::string describe(const Timing &timing) {
  std::vector<std::string> parts;
  if (timing.period)
    parts.push_back("period " + format_duration(*timing.period));
  if (timing.deadline)
    parts.push_back("deadline " + format_duration(*timing.deadline));
  if (timing.execution_time)
    parts.push_back("execution " + format_duration(*timing.execution_time));
  if (timing.priority)
    parts.push_back(fmt::format("priority {}", *timing.priority));
  if (timing.criticality)
    parts.push_back(fmt::format("criticality {}", to_string(*timing.criticality)));
  return fmt::format("{}", fmt::join(parts, ", "));
}

void show_application(Tree &t, const ResolvedApplication &app) {
  const SoftwareAssembly &sad = *app.sad;
  t.line(0, fmt::format("application {} {} ({})", sad.name, sad.version, app.sad_path.string()));
  t.line(1, "assembly controller: " + sad.assembly_controller);
  t.line(1, "components:");
  for (const auto &placement : sad.placements) {
    const ResolvedSoftPkg *pkg = app.softpkg_of(placement);
    for (const auto &ci : placement.instantiations) {
      std::string extra = ci.start_order ? fmt::format(" startorder {}", *ci.start_order) : "";
      if (!placement.host_collocation.empty())
        extra += " hostcollocation " + placement.host_collocation;
      t.line(2, fmt::format("{}{}", ci.id, extra));
      if (ci.timing)
        t.line(3, "timing: " + describe(*ci.timing));
      for (const auto &ref : ci.properties)
        if (const auto *def = pkg != nullptr ? pkg->find_property(refid_of(ref)) : nullptr)
          if (auto value = bind_property(*def, ref))
            t.line(3, fmt::format("override {} = {}", refid_of(ref), format_value(*value)));
      if (pkg != nullptr)
        show_softpkg(t, 3, *pkg);
    }
  }
  if (!sad.connections.empty())
    t.line(1, "connections:");
  for (const auto &c : sad.connections) {
    std::string line = fmt::format("{}: {} -> {}", c.id.empty() ? "(unnamed)" : c.id,
                                   describe(c.uses.target, c.uses.port),
                                   describe(c.provides.target, c.provides.port));
    if (c.qos)
      line += " [" + describe(*c.qos) + "]";
    if (c.filter)
      line += " filter \"" + *c.filter + "\"";
    t.line(2, line);
  }
  for (const auto &p : sad.external_ports)
    t.line(1, fmt::format("external port {} = {}.{}", p.external_name, p.component_ref, p.port));
  for (const auto &p : sad.external_properties)
    t.line(1, fmt::format("external property {} = {}.{}", p.external_id, p.component_ref,
                          p.property_id));
  for (const auto &p : sad.latency_paths)
    t.line(1, fmt::format("latency path {} <= {}: {}", p.id, format_duration(p.bound),
                          fmt::join(p.components, " -> ")));
}

void show_node(Tree &t, const ResolvedNode &node) {
  t.line(0, fmt::format("node {} ({})", node.dcd->name, node.dcd_path.string()));
  for (const auto &device : node.devices) {
    for (const auto &ci : device.placement->instantiations)
      t.line(1, fmt::format("device {} ({})", ci.id, ci.usage_name));
    if (device.device_pkg)
      t.line(2, fmt::format("hardware: {} {} ({})", device.device_pkg->hardware.manufacturer,
                            device.device_pkg->hardware.model_number,
                            fmt::join(device.device_pkg->hardware.device_classes, ", ")));
    if (device.softpkg)
      show_softpkg(t, 2, *device.softpkg);
  }
}

// A running application's name: a folder of that name here is no profile (a profile is a file),
// so the application is shown, and the note says so.
int show_running(const std::string &name, const GraphOptions &graph, const GlobalOptions &global) {
  std::error_code ec;
  if (fs::is_directory(name, ec) && !global.json)
    fmt::print(stderr,
               "rsca show: showing the running application {}, not the folder {} here (a "
               "profile is a file)\n",
               name, name);
  if (!graph.format.empty())
    return show_application_graph(name, graph, global);
  return show_application(name, global);
}

int run(const std::string &path, const GraphOptions &graph, const GlobalOptions &global) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    return show_running(path, graph, global);
  if (!graph.format.empty())
    return fail(global, "show", kUsage,
                fmt::format("--graph draws a running application, and {} is a file", path));
  std::optional<fs::path> sdrroot;
  if (!global.sdrroot.empty())
    sdrroot = global.sdrroot;
  ProfileLoader loader(sdrroot);
  auto descriptor = loader.validate(path);
  if (!descriptor) {
    if (global.json)
      return fail(global, "show", kInvalidProfile, descriptor.error().to_string());
    fmt::print(stderr, "{}\n", descriptor.error().to_string());
    return kInvalidProfile;
  }
  Tree t;
  nlohmann::json warnings = nlohmann::json::array();
  for (const auto &w : descriptor->warnings) {
    warnings.push_back(to_string(w));
    if (!global.json)
      fmt::print(stderr, "{}\n", to_string(w));
  }
  switch (type_of(descriptor->descriptor)) {
  case DescriptorType::SAD:
    show_application(t, *loader.load_application(path));
    break;
  case DescriptorType::DCD:
    show_node(t, *loader.load_node(path));
    break;
  case DescriptorType::SPD:
    show_softpkg(t, 0, **loader.load_softpkg(path));
    break;
  case DescriptorType::PRF:
    show_properties(t, 0, std::get<Properties>(descriptor->descriptor));
    break;
  case DescriptorType::SCD:
    show_ports(t, 0, std::get<SoftwareComponent>(descriptor->descriptor));
    break;
  case DescriptorType::DMD: {
    const auto &dmd = std::get<DomainManagerConfiguration>(descriptor->descriptor);
    t.line(0, fmt::format("domain {} ({})", dmd.name, dmd.id));
    break;
  }
  case DescriptorType::DPD: {
    const auto &dpd = std::get<DevicePkg>(descriptor->descriptor);
    t.line(0, fmt::format("device package {}: {} {}", dpd.name, dpd.hardware.manufacturer,
                          dpd.hardware.model_number));
    break;
  }
  }
  if (global.json)
    std::cout << nlohmann::json{{"path", path}, {"warnings", warnings}, {"tree", t.json()}}.dump(2)
              << '\n';
  else
    std::cout << t.str();
  return kOk;
}

} // namespace

void add_show_command(CLI::App &app, const GlobalOptions &global, int &exit_code) {
  auto *cmd =
      app.add_subcommand("show", "Show a profile's resolved model, or a running application");
  auto path = std::make_shared<std::string>();
  cmd->add_option("what", *path,
                  "Profile file (SAD, SPD, SCD, PRF, DCD, DMD or DPD) or application name")
      ->required();
  auto graph = std::make_shared<GraphOptions>();
  auto *format = cmd->add_option("--graph", graph->format,
                                 "A running application's picture: dot (Graphviz's text) or svg "
                                 "(drawn by Graphviz's dot, of the Debian package graphviz)")
                     ->check(CLI::IsMember({"dot", "svg"}));
  cmd->add_option("-o,--out,--output", graph->output, "Write the picture to this file, not stdout")
      ->needs(format);
  cmd->callback([path, graph, &global, &exit_code] { exit_code = run(*path, *graph, global); });
}

} // namespace rsca::cli
