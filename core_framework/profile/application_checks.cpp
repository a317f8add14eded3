#include "profile/application_checks.hpp"

#include <cstdint>
#include <optional>
#include <set>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "common/names.hpp"
#include "profile/code_description.hpp"
#include "profile/profile_loader.hpp"
#include "profile/property_binding.hpp"

namespace rsca::profile {
namespace {

std::string file_name(const std::filesystem::path &p) {
  return p.filename().string();
}

// What an override whose value does not fit its property is: an error in a SAD (the launch would
// configure the component with it), ignored with a warning in a DCD (REDHAWK's DeviceManager logs
// it and starts the device with its default; rsca's node skips it the same way).
enum class BadValue : std::uint8_t { Refused, Ignored };

// The ids of every property a package defines (its PRF's and its implementations').
std::vector<std::string> property_ids(const ResolvedSoftPkg &pkg) {
  std::vector<std::string> ids;
  auto add = [&](const std::shared_ptr<const Properties> &prf) {
    if (prf)
      for (const auto &p : prf->properties)
        ids.push_back(common_of(p).id);
  };
  add(pkg.properties);
  for (const auto &impl : pkg.implementations)
    add(impl.properties);
  return ids;
}

// The override of a property the package lacks: a warning (REDHAWK ignores the override), which
// a profile written for rsca, or --strict, refuses.
Diagnostic unknown_property(const ResolvedSoftPkg &pkg, const PropertyRef &ref,
                            std::string_view owner) {
  const std::string close = closest_name(refid_of(ref), property_ids(pkg));
  return {location_of(ref), "unknown-property",
          fmt::format("{}: property \"{}\" is not defined by {}{}: the override is ignored "
                      "(REDHAWK's way; a profile written for rsca, or --strict, refuses it)",
                      owner, refid_of(ref),
                      pkg.properties ? file_name(pkg.properties->file)
                                     : file_name(pkg.spd_path) + " (it has no PRF)",
                      close.empty() ? "" : fmt::format(" (did you mean \"{}\"?)", close)),
          Severity::Warning};
}

// Each override must carry a value that fits its property; one that names no property of the
// package is ignored with a warning, as REDHAWK does. A package whose files are missing is not
// checked: its missing files are reported already.
void check_property_refs(const ResolvedSoftPkg &pkg, const std::vector<PropertyRef> &refs,
                         std::string_view owner, BadValue bad_value, Error &errors,
                         std::vector<Diagnostic> &tolerated) {
  if (!pkg.unavailable.empty() && pkg.properties == nullptr)
    return;
  for (const auto &ref : refs) {
    const PropertyDefinition *definition = pkg.find_property(refid_of(ref));
    if (definition == nullptr) {
      tolerated.push_back(unknown_property(pkg, ref, owner));
      continue;
    }
    if (is_empty_override(*definition, ref)) {
      tolerated.push_back({location_of(ref), "empty-value",
                           fmt::format("{}: property \"{}\" is given an empty value: the override "
                                       "is ignored, as REDHAWK does",
                                       owner, refid_of(ref)),
                           Severity::Warning});
      continue;
    }
    auto bound = bind_property(*definition, ref);
    if (bound)
      continue;
    if (bad_value == BadValue::Refused && !names_unknown_members_only(bound.error())) {
      errors.append(bound.error());
      continue;
    }
    for (auto d : bound.error().diagnostics()) {
      d.severity = Severity::Warning;
      d.message = fmt::format("{}: {}: the override is ignored", owner, d.message);
      tolerated.push_back(std::move(d));
    }
  }
}

class ApplicationChecker {
public:
  ApplicationChecker(const ResolvedApplication &app, Error &errors,
                     std::vector<Diagnostic> &tolerated)
      : app_(app), errors_(errors), tolerated_(tolerated) {}

  // Wiring problems: reported as warnings (see Severity).
  void warn(SourceLocation where, std::string rule, std::string message) {
    errors_.add({std::move(where), std::move(rule), std::move(message), Severity::Warning});
  }

  void run() {
    for (const auto &placement : app_.sad->placements)
      for (const auto &ci : placement.instantiations)
        if (const ResolvedSoftPkg *pkg = app_.softpkg_of(placement))
          check_property_refs(*pkg, ci.properties,
                              fmt::format("componentinstantiation \"{}\"", ci.id),
                              BadValue::Refused, errors_, tolerated_);
    for (const auto &c : app_.sad->connections)
      check_connection(c);
    for (const auto &p : app_.sad->external_ports)
      check_external_port(p);
    for (const auto &p : app_.sad->external_properties)
      check_external_property(p);
  }

private:
  // The SCD of a component instantiation; reports and returns nullptr when there is none.
  const SoftwareComponent *scd_of(const std::string &instance, const SourceLocation &where,
                                  const std::string &what) {
    const ComponentPlacement *placement = nullptr;
    if (app_.sad->find_instantiation(instance, &placement) == nullptr)
      return nullptr; // already reported by the SAD reader
    const ResolvedSoftPkg *pkg = app_.softpkg_of(*placement);
    if (pkg == nullptr)
      return nullptr;
    if (!pkg->scd && !pkg->unavailable.empty())
      return nullptr; // its missing files are reported, and refuse its launch
    if (!pkg->scd)
      warn(where, "missing-scd",
           fmt::format("{}: component \"{}\" ({}) has no SCD, so its ports are unknown", what,
                       instance, file_name(pkg->spd_path)));
    return pkg->scd.get();
  }

  const PortDefinition *check_port(const std::string &instance, const std::string &port,
                                   PortDirection direction, const SourceLocation &where,
                                   const std::string &what) {
    const SoftwareComponent *scd = scd_of(instance, where, what);
    if (scd == nullptr)
      return nullptr;
    const PortDefinition *def = scd->find_port(port, direction);
    if (def != nullptr)
      return def;
    std::vector<std::string> names;
    for (const auto &p : scd->ports)
      if (p.direction == direction)
        names.push_back(p.name);
    const auto kind = to_string(direction);
    warn(where, "unknown-port",
         fmt::format("{}: component \"{}\" has no {} port \"{}\" ({} ports: {})", what, instance,
                     kind, port, kind,
                     names.empty() ? std::string("none")
                                   : fmt::format("{}", fmt::join(names, ", "))));
    return nullptr;
  }

  void check_connection(const Connection &c) {
    const std::string what =
        c.id.empty() ? std::string("connection") : fmt::format("connection \"{}\"", c.id);
    const PortDefinition *uses = nullptr;
    if (c.uses.target.kind == EndpointTarget::Kind::ComponentInstantiation)
      uses = check_port(c.uses.target.refid, c.uses.port, PortDirection::Uses, c.uses.where, what);
    if (c.provides.target.kind != EndpointTarget::Kind::ComponentInstantiation)
      return;
    if (c.provides.kind == ProvidesEnd::Kind::SupportedInterface) {
      check_supported_interface(c.provides.target.refid, c.provides.port, c.provides.where, what);
      if (uses != nullptr)
        check_interface_call(c, *uses, what);
      return;
    }
    const PortDefinition *provides = check_port(c.provides.target.refid, c.provides.port,
                                                PortDirection::Provides, c.provides.where, what);
    if (uses != nullptr && provides != nullptr && uses->repid != provides->repid)
      warn(c.where, "port-type",
           fmt::format("{}: uses port {}.{} sends {}, but provides port {}.{} takes {}", what,
                       c.uses.target.refid, uses->name, uses->repid, c.provides.target.refid,
                       provides->name, provides->repid));
  }

  void check_external_port(const ExternalPort &p) {
    const std::string what = fmt::format("external port \"{}\"", p.external_name);
    if (p.kind == ExternalPort::Kind::SupportedInterface) {
      check_supported_interface(p.component_ref, p.port, p.where, what);
      return;
    }
    check_port(p.component_ref, p.port,
               p.kind == ExternalPort::Kind::Uses ? PortDirection::Uses : PortDirection::Provides,
               p.where, what);
  }

  void check_supported_interface(const std::string &instance, const std::string &repid,
                                 const SourceLocation &where, const std::string &what) {
    const SoftwareComponent *scd = scd_of(instance, where, what);
    if (scd != nullptr && !scd->supports(repid))
      warn(
          where, "unknown-interface",
          fmt::format("{}: component \"{}\" does not support interface {}", what, instance, repid));
  }

  // A uses port connected to a component's supported interface calls it through the control
  // plane: its repid must be a CF interface rsca serves, and one the component supports.
  void check_interface_call(const Connection &c, const PortDefinition &uses,
                            const std::string &what) {
    if (c.uses.target.refid == c.provides.target.refid) {
      // Its calls would wait for its own property lock, held while it calls.
      warn(c.where, "self-call",
           fmt::format("{}: component \"{}\" cannot call its own supported interface", what,
                       c.uses.target.refid));
      return;
    }
    if (!is_control_interface(uses.repid)) {
      warn(c.where, "port-type",
           fmt::format("{}: uses port {}.{} is of {}, which cannot call a component's supported "
                       "interface (a port of IDL:CF/Resource:1.0 or an interface it inherits can)",
                       what, c.uses.target.refid, uses.name, uses.repid));
      return;
    }
    const ComponentPlacement *placement = nullptr;
    if (app_.sad->find_instantiation(c.provides.target.refid, &placement) == nullptr)
      return;
    const ResolvedSoftPkg *pkg = app_.softpkg_of(*placement);
    if (pkg != nullptr && pkg->scd && !pkg->scd->supports(uses.repid))
      warn(c.where, "port-type",
           fmt::format("{}: uses port {}.{} calls {}, which component \"{}\" does not support",
                       what, c.uses.target.refid, uses.name, uses.repid, c.provides.target.refid));
  }

  void check_external_property(const ExternalProperty &p) {
    const ComponentPlacement *placement = nullptr;
    if (app_.sad->find_instantiation(p.component_ref, &placement) == nullptr)
      return;
    const ResolvedSoftPkg *pkg = app_.softpkg_of(*placement);
    if (pkg != nullptr && pkg->unavailable.empty() && pkg->find_property(p.property_id) == nullptr)
      errors_.add({p.where, "unknown-property",
                   fmt::format("external property \"{}\": component \"{}\" has no property \"{}\"",
                               p.external_id, p.component_ref, p.property_id)});
  }

  const ResolvedApplication &app_;
  Error &errors_;
  std::vector<Diagnostic> &tolerated_;
};

// Each component whose package misses a file it needs to run.
std::vector<Diagnostic> missing_files(const ResolvedApplication &app) {
  std::vector<Diagnostic> out;
  for (const auto &placement : app.sad->placements) {
    const auto *pkg = app.softpkg_of(placement);
    if (pkg == nullptr)
      continue;
    for (const auto &ci : placement.instantiations)
      for (const auto &missing : pkg->unavailable)
        out.push_back({missing.where, missing.rule,
                       fmt::format("component {} cannot be launched: {}", ci.id, missing.message)});
  }
  return out;
}

// One end of a connection that rsca cannot connect: why, or nothing.
std::optional<std::string> unsupported_end(const SoftwareAssembly &sad, const EndpointTarget &end) {
  using Kind = EndpointTarget::Kind;
  if (end.kind == Kind::FindBy && !end.findby.is_event_channel())
    return fmt::format("only event channels can be found by findby; \"{}\" is not one",
                       end.findby.name);
  if (end.kind == Kind::ComponentInstantiation && sad.find_instantiation(end.refid) == nullptr)
    return fmt::format("\"{}\" is no component of the application (a DeviceManager, to "
                       "REDHAWK): rsca cannot connect to it",
                       end.refid);
  return std::nullopt;
}

// Why rsca cannot make connection `c` yet, each reason once.
std::vector<std::string> unsupported_reasons(const SoftwareAssembly &sad, const Connection &c) {
  using Kind = EndpointTarget::Kind;
  std::vector<std::string> out;
  for (const auto *end : {&c.uses.target, &c.provides.target})
    if (auto why = unsupported_end(sad, *end))
      out.push_back(std::move(*why));
  const auto is_device = [](const EndpointTarget &t) {
    return t.kind == Kind::DeviceThatLoadedThisComponent ||
           t.kind == Kind::DeviceUsedByThisComponent || t.kind == Kind::DeviceUsedByApplication;
  };
  if ((c.publishes_to_channel() && is_device(c.uses.target)) ||
      (c.subscribes_to_channel() && is_device(c.provides.target)))
    out.emplace_back("a device port cannot be an event channel member yet: connect it to a "
                     "component port");
  if (c.provides.kind == ProvidesEnd::Kind::SupportedInterface &&
      (c.uses.target.kind != Kind::ComponentInstantiation ||
       c.provides.target.kind != Kind::ComponentInstantiation))
    out.emplace_back("a supported interface connects a component's uses port to another "
                     "component of the application (componentinstantiationref on both sides), "
                     "not to a device or a channel");
  return out;
}

std::vector<Diagnostic> unsupported_connections(const SoftwareAssembly &sad) {
  std::vector<Diagnostic> out;
  for (std::size_t i = 0; i < sad.connections.size(); ++i) {
    const auto &c = sad.connections[i];
    for (auto &why : unsupported_reasons(sad, c))
      out.push_back({c.where, "unsupported-connection",
                     fmt::format("connection {}: {}", connection_id(c, i), why)});
  }
  return out;
}

} // namespace

std::vector<Diagnostic> check_application(const ResolvedApplication &app,
                                          std::vector<Diagnostic> &tolerated) {
  Error findings;
  ApplicationChecker(app, findings, tolerated).run();
  return findings.diagnostics();
}

std::vector<Diagnostic> check_node(const ResolvedNode &node, std::vector<Diagnostic> &tolerated) {
  Error errors;
  std::set<std::string> instance_ids;
  for (const auto &device : node.devices)
    for (const auto &ci : device.placement->instantiations)
      instance_ids.insert(ci.id);
  for (const auto &device : node.devices) {
    const ComponentPlacement &placement = *device.placement;
    for (const auto *parent : {&placement.deploy_on_device, &placement.composite_part_of_device})
      if (!parent->empty() && instance_ids.count(*parent) == 0)
        errors.add({placement.ref_where, "dangling-ref",
                    fmt::format("the placement names device \"{}\", which this DCD does not define",
                                *parent)});
    if (!device.softpkg)
      continue;
    for (const auto &ci : placement.instantiations) {
      check_property_refs(*device.softpkg, ci.properties, fmt::format("device \"{}\"", ci.id),
                          BadValue::Ignored, errors, tolerated);
    }
  }
  return errors.diagnostics();
}

std::vector<Diagnostic> launch_refusals(const ResolvedApplication &app) {
  if (auto missing = missing_files(app); !missing.empty())
    return missing;
  if (auto misfits = code_refusals(app); !misfits.empty())
    return misfits; // its component would exit at start, saying the same
  auto as_errors = [](std::vector<Diagnostic> findings) {
    for (auto &d : findings)
      d.severity = Severity::Error;
    return findings;
  };
  if (!app.warnings.empty())
    return as_errors(app.warnings);
  if (is_strict(app) && !app.tolerated.empty())
    return as_errors(app.tolerated);
  return unsupported_connections(*app.sad);
}

bool is_strict(const ResolvedApplication &app) {
  return !app.sad->redhawk;
}

std::string connection_id(const Connection &c, std::size_t index) {
  return c.id.empty() ? fmt::format("connection_{}", index + 1) : c.id;
}

} // namespace rsca::profile
