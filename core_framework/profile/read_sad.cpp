// SAD reader: the application and the references between its own parts.
#include <algorithm>
#include <charconv>
#include <cmath>

#include "common/names.hpp"
#include "common/text.hpp"
#include "profile/read_context.hpp"
#include "profile/sad.hpp"

namespace rsca::profile {
namespace {

using detail::ReadContext;

// More cores than any robot computer has: a larger reservation is a mistake.
constexpr double kMaxReservedCores = 4096;

// A reservation of kind cpucores (REDHAWK's one kind) is a number of cores; another kind is
// read with a warning and ignored, as rsca reserves nothing for it.
void read_reservation(ReadContext &ctx, const XmlElement &e, HostCollocation &hc) {
  const std::string &kind = e.attr("kind");
  if (kind != "cpucores") {
    ctx.warn(
        e, "unknown-value",
        fmt::format("reservation kind \"{}\" is not one rsca reserves (cpucores): ignored", kind));
    return;
  }
  const std::string_view value = trim(e.attr("value"));
  double cores = 0;
  const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), cores);
  if (ec != std::errc() || end != value.data() + value.size() || !std::isfinite(cores) ||
      cores < 0 || cores > kMaxReservedCores) {
    ctx.fail(e, "value",
             fmt::format("reservation value \"{}\" is not a number of cores", e.attr("value")));
    return;
  }
  if (hc.cpu_cores)
    ctx.warn(e, "reservation", "a second cpucores reservation: the larger one counts");
  hc.cpu_cores = std::max(hc.cpu_cores.value_or(0.0), cores);
}

void read_partitioning(ReadContext &ctx, const XmlElement &e, SoftwareAssembly &sad) {
  std::set<std::string> collocation_ids;
  for (const auto &c : e.children) {
    if (c.name == "componentplacement") {
      sad.placements.push_back(detail::read_component_placement(ctx, c));
      continue;
    }
    if (c.name != "hostcollocation")
      continue;
    HostCollocation hc{c.attr("id"), c.attr("name"), {}, ctx.at(c), {}, {}, std::nullopt};
    if (!hc.id.empty()) {
      hc.key = hc.id;
      ctx.require_unique(collocation_ids, hc.id, c, "hostcollocation id");
    } else {
      // No id: its name, or its place when the name is empty or taken.
      hc.key = hc.name;
      if (hc.key.empty() || !collocation_ids.insert(hc.key).second)
        hc.key = fmt::format("{}#{}", hc.name, sad.host_collocations.size() + 1);
    }
    for (const auto &p : c.children) {
      if (p.name == "usesdeviceref") {
        hc.uses_device_refs.push_back(p.attr("refid"));
        hc.uses_device_ref_where.push_back(ctx.at(p));
      } else if (p.name == "reservation") {
        read_reservation(ctx, p, hc);
      } else if (p.name == "componentplacement") {
        sad.placements.push_back(detail::read_component_placement(ctx, p));
        sad.placements.back().host_collocation = hc.key;
      }
    }
    sad.host_collocations.push_back(std::move(hc));
  }
}

void read_external_ports(ReadContext &ctx, const XmlElement &e, SoftwareAssembly &sad) {
  for (const auto &p : e.children) {
    ExternalPort port;
    port.where = ctx.at(p);
    for (const auto &c : p.children) {
      if (c.name == "usesidentifier") {
        port.port = c.trimmed_text();
        port.kind = ExternalPort::Kind::Uses;
      } else if (c.name == "providesidentifier") {
        port.port = c.trimmed_text();
        port.kind = ExternalPort::Kind::Provides;
      } else if (c.name == "supportedidentifier") {
        port.port = c.trimmed_text();
        port.kind = ExternalPort::Kind::SupportedInterface;
      } else if (c.name == "componentinstantiationref") {
        port.component_ref = c.attr("refid");
      }
    }
    const std::string *external = p.attribute("externalname");
    port.external_name = external != nullptr ? *external : port.port;
    sad.external_ports.push_back(std::move(port));
  }
}

void read_external_properties(ReadContext &ctx, const XmlElement &e, SoftwareAssembly &sad) {
  for (const auto &p : e.children) {
    const std::string *external = p.attribute("externalpropid");
    sad.external_properties.push_back({p.attr("comprefid"), p.attr("propid"),
                                       external != nullptr ? *external : p.attr("propid"),
                                       ctx.at(p)});
  }
}

void read_latency_paths(ReadContext &ctx, const XmlElement &e, SoftwareAssembly &sad) {
  for (const auto &p : e.children) {
    LatencyPath path;
    path.id = p.attr("id");
    path.where = ctx.at(p);
    path.bound = ctx.duration_attr(p, "bound").value_or(Duration{});
    for (const auto &c : p.children) {
      if (c.name != "componentinstantiationref")
        continue;
      path.components.push_back(c.attr("refid"));
      path.component_where.push_back(ctx.at(c));
    }
    sad.latency_paths.push_back(std::move(path));
  }
}

// References from the SAD's tail sections to component instantiations.
void check_instance_refs(ReadContext &ctx, const SoftwareAssembly &sad) {
  auto require = [&](const std::string &refid, const SourceLocation &where, std::string_view what) {
    if (sad.find_instantiation(refid) == nullptr)
      ctx.report({where, "dangling-ref",
                  fmt::format("{} names componentinstantiation \"{}\", which this SAD does not "
                              "define",
                              what, refid)});
  };
  require(sad.assembly_controller, sad.assembly_controller_where, "assemblycontroller");
  for (const auto &p : sad.external_ports)
    require(p.component_ref, p.where, fmt::format("external port \"{}\"", p.external_name));
  std::set<std::string> external_ids;
  for (const auto &p : sad.external_properties) {
    require(p.component_ref, p.where, fmt::format("external property \"{}\"", p.external_id));
    if (!external_ids.insert(p.external_id).second)
      ctx.report(
          {p.where, "duplicate-id",
           fmt::format("external property \"{}\" is defined more than once", p.external_id)});
  }
  for (const auto &path : sad.latency_paths)
    for (std::size_t i = 0; i < path.components.size(); ++i)
      require(path.components[i], path.component_where[i],
              fmt::format("latency path \"{}\"", path.id));
}

// References to the SAD's own usesdevice: from a host collocation (usesdeviceref) and from a
// connection end (deviceusedbyapplication).
void check_uses_device_refs(ReadContext &ctx, const SoftwareAssembly &sad) {
  std::set<std::string> ids;
  for (const auto &u : sad.uses_device_dependencies)
    ctx.require_unique(ids, u.id, u.where, "usesdevice id");
  auto require = [&](const std::string &usesrefid, const SourceLocation &where,
                     std::string_view what) {
    if (ids.count(usesrefid) == 0)
      ctx.report({where, "dangling-ref",
                  fmt::format("{} names usesdevice \"{}\", which this SAD's "
                              "usesdevicedependencies do not define",
                              what, usesrefid)});
  };
  for (const auto &hc : sad.host_collocations)
    for (std::size_t i = 0; i < hc.uses_device_refs.size(); ++i)
      require(hc.uses_device_refs[i], hc.uses_device_ref_where[i],
              fmt::format("hostcollocation \"{}\"", hc.id.empty() ? hc.name : hc.id));
  for (const auto &c : sad.connections)
    for (const auto *end : {&c.uses.target, &c.provides.target})
      if (end->kind == EndpointTarget::Kind::DeviceUsedByApplication)
        require(end->usesrefid, end->where, "deviceusedbyapplication");
}

} // namespace

Expected<SoftwareAssembly> read_sad(const XmlDocument &document) {
  ReadContext ctx(document);
  const XmlElement &root = document.root;
  SoftwareAssembly sad;
  sad.file = document.file;
  sad.id = root.attr("id");
  sad.name = root.attr("name");
  sad.version = root.attr("version");
  // The name the application is installed and runs under (the id when it has none) becomes a
  // folder of the domain's repository and part of control addresses: it must be a name.
  if (auto named = check_name("the application", sad.name.empty() ? sad.id : sad.name); !named)
    ctx.fail(root, "application-name", named.error().diagnostics().front().message);
  sad.description = root.child_text("description");
  sad.component_files = detail::read_component_files(ctx, root.child("componentfiles"));
  for (const auto &c : root.children) {
    if (c.name == "partitioning") {
      read_partitioning(ctx, c, sad);
    } else if (c.name == "assemblycontroller") {
      if (const XmlElement *ref = c.child("componentinstantiationref")) {
        sad.assembly_controller = ref->attr("refid");
        sad.assembly_controller_where = ctx.at(*ref);
      }
    } else if (c.name == "connections") {
      sad.connections = detail::read_connections(ctx, &c);
    } else if (c.name == "externalports") {
      read_external_ports(ctx, c, sad);
    } else if (c.name == "externalproperties") {
      read_external_properties(ctx, c, sad);
    } else if (c.name == "usesdevicedependencies") {
      for (const auto &u : c.children)
        sad.uses_device_dependencies.push_back(
            {u.attr("id"), u.attr("type"), detail::read_property_refs(ctx, &u), ctx.at(u)});
    } else if (c.name == "latencyconstraints") {
      read_latency_paths(ctx, c, sad);
    }
  }
  detail::check_assembly_references(ctx, sad.component_files, sad.placements, sad.connections);
  check_instance_refs(ctx, sad);
  check_uses_device_refs(ctx, sad);
  return detail::finish(ctx, std::move(sad));
}

} // namespace rsca::profile
