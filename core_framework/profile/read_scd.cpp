// SCD reader: ports and interfaces.
#include "profile/read_context.hpp"
#include "profile/scd.hpp"

namespace rsca::profile {
namespace {

using detail::ReadContext;

void read_ports(ReadContext &ctx, const XmlElement &ports, SoftwareComponent &scd) {
  std::set<std::string> names;
  for (const auto &p : ports.children) {
    const auto direction = port_direction_from_name(p.name);
    if (!direction)
      continue;
    PortDefinition port;
    port.direction = *direction;
    port.name = p.attr(p.name == "uses" ? "usesname" : "providesname");
    port.repid = p.attr("repid");
    port.description = p.child_text("description");
    port.where = ctx.at(p);
    for (const auto &t : p.children)
      if (t.name == "porttype")
        port.port_types.push_back(t.attr("type"));
    // A uses and a provides port may share a name in SCA; two of one direction may not.
    ctx.require_unique(names, std::string(p.name) + ":" + port.name, p,
                       fmt::format("{} port", p.name));
    scd.ports.push_back(std::move(port));
  }
}

} // namespace

Expected<SoftwareComponent> read_scd(const XmlDocument &document) {
  ReadContext ctx(document);
  const XmlElement &root = document.root;
  SoftwareComponent scd;
  scd.file = document.file;
  scd.corba_version = root.child_text("corbaversion");
  if (const XmlElement *repid = root.child("componentrepid"))
    scd.component_repid = repid->attr("repid");
  scd.component_type = root.child_text("componenttype");
  if (const XmlElement *pf = root.child("propertyfile")) {
    ctx.expect_type(*pf, "PRF");
    scd.property_file = detail::read_localfile(ctx, *pf).name;
  }
  if (const XmlElement *features = root.child("componentfeatures")) {
    for (const auto &c : features->children)
      if (c.name == "supportsinterface")
        scd.supported_interfaces.push_back({c.attr("repid"), c.attr("supportsname")});
    if (const XmlElement *ports = features->child("ports"))
      read_ports(ctx, *ports, scd);
  }
  if (const XmlElement *interfaces = root.child("interfaces")) {
    for (const auto &i : interfaces->children) {
      InterfaceDefinition def{i.attr("name"), i.attr("repid"), {}};
      for (const auto &inh : i.children)
        if (inh.name == "inheritsinterface")
          def.inherits.push_back(inh.attr("repid"));
      scd.interfaces.push_back(std::move(def));
    }
  }
  return detail::finish(ctx, std::move(scd));
}

} // namespace rsca::profile
