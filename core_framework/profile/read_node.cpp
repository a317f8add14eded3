// Readers of the node and domain descriptors: DCD, DMD and DPD.
#include "profile/dcd.hpp"
#include "profile/dmd.hpp"
#include "profile/dpd.hpp"
#include "profile/read_context.hpp"

namespace rsca::profile {
namespace {

using detail::ReadContext;

HardwareDevice read_hardware(ReadContext &ctx, const XmlElement &e) {
  HardwareDevice hw;
  hw.id = e.attr("id");
  hw.name = e.attr("name");
  hw.version = e.attr("version");
  hw.description = e.child_text("description");
  hw.manufacturer = e.child_text("manufacturer");
  hw.model_number = e.child_text("modelnumber");
  for (const auto &c : e.children) {
    if (c.name == "propertyfile") {
      ctx.expect_type(c, "PRF");
      hw.property_file = detail::read_localfile(ctx, c);
    } else if (c.name == "deviceclass") {
      for (const auto &cls : c.children)
        if (cls.name == "class")
          hw.device_classes.push_back(cls.trimmed_text());
    } else if (c.name == "childhwdevice") {
      for (const auto &child : c.children)
        if (child.name == "hwdeviceregistration")
          hw.children.push_back(read_hardware(ctx, child));
    }
  }
  return hw;
}

} // namespace

Expected<DeviceConfiguration> read_dcd(const XmlDocument &document) {
  ReadContext ctx(document);
  const XmlElement &root = document.root;
  DeviceConfiguration dcd;
  dcd.file = document.file;
  dcd.id = root.attr("id");
  dcd.name = root.attr("name");
  dcd.description = root.child_text("description");
  if (const XmlElement *mgr = root.child("devicemanagersoftpkg"))
    dcd.device_manager_softpkg = detail::read_localfile(ctx, *mgr);
  dcd.component_files = detail::read_component_files(ctx, root.child("componentfiles"));
  if (const XmlElement *partitioning = root.child("partitioning"))
    for (const auto &c : partitioning->children)
      if (c.name == "componentplacement")
        dcd.placements.push_back(detail::read_component_placement(ctx, c));
  dcd.connections = detail::read_connections(ctx, root.child("connections"));
  if (const XmlElement *dm = root.child("domainmanager"))
    if (const XmlElement *ns = dm->child("namingservice"))
      dcd.domain_manager = ns->attr("name");
  detail::check_assembly_references(ctx, dcd.component_files, dcd.placements, dcd.connections);
  return detail::finish(ctx, std::move(dcd));
}

Expected<DomainManagerConfiguration> read_dmd(const XmlDocument &document) {
  ReadContext ctx(document);
  const XmlElement &root = document.root;
  DomainManagerConfiguration dmd;
  dmd.file = document.file;
  dmd.id = root.attr("id");
  dmd.name = root.attr("name");
  dmd.description = root.child_text("description");
  if (const XmlElement *mgr = root.child("domainmanagersoftpkg"))
    dmd.domain_manager_softpkg = detail::read_localfile(ctx, *mgr);
  return detail::finish(ctx, std::move(dmd));
}

Expected<DevicePkg> read_dpd(const XmlDocument &document) {
  ReadContext ctx(document);
  const XmlElement &root = document.root;
  DevicePkg dpd;
  dpd.file = document.file;
  dpd.id = root.attr("id");
  dpd.name = root.attr("name");
  dpd.version = root.attr("version");
  dpd.title = root.child_text("title");
  dpd.description = root.child_text("description");
  for (const auto &c : root.children)
    if (c.name == "author")
      dpd.authors.push_back(c.child_text("name"));
  if (const XmlElement *hw = root.child("hwdeviceregistration"))
    dpd.hardware = read_hardware(ctx, *hw);
  return detail::finish(ctx, std::move(dpd));
}

} // namespace rsca::profile
