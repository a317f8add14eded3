// SPD reader: implementations, their dependencies and RSCA resource demands.
#include <charconv>

#include "profile/read_context.hpp"
#include "profile/spd.hpp"

namespace rsca::profile {
namespace {

using detail::ReadContext;

tl::expected<double, std::string> parse_utilization(std::string_view text) {
  double value = 0;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size())
    return tl::unexpected(fmt::format("\"{}\" is not a number", text));
  if (!(value > 0 && value <= 1))
    return tl::unexpected(fmt::format("{} is not a utilization in (0, 1]", text));
  return value;
}

tl::expected<std::uint64_t, std::string> parse_count(std::string_view text) {
  std::uint64_t value = 0;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size())
    return tl::unexpected(fmt::format("\"{}\" is not a non-negative integer", text));
  return value;
}

// An os or processor the implementation needs; an empty name (which REDHAWK's tools can write)
// would match no device, and is ignored with a warning.
void read_os_or_processor(ReadContext &ctx, const XmlElement &e, Implementation &impl) {
  const std::string &name = e.attr("name");
  if (name.find_first_not_of(" \t\r\n") == std::string::npos) {
    ctx.warn(e, "empty-value", fmt::format("<{}> with no name: ignored", e.name));
    return;
  }
  if (e.name == "os")
    impl.os.push_back({name, e.attr("version")});
  else
    impl.processors.push_back(name);
}

ResourceDemand read_resource_demand(ReadContext &ctx, const XmlElement &e) {
  ResourceDemand d;
  d.where = ctx.at(e);
  d.utilization = ctx.optional_attr(e, "utilization", parse_utilization);
  d.execution_time = ctx.duration_attr(e, "executiontime");
  d.period = ctx.duration_attr(e, "period");
  d.memory_bytes = ctx.optional_attr(e, "memory", parse_size_bytes);
  d.bandwidth_bps = ctx.optional_attr(e, "bandwidth", parse_bitrate_bps);
  if (d.utilization && d.execution_time)
    ctx.fail(e, "resourcedemand",
             "give CPU demand either as utilization or as executiontime per period, not both");
  if (d.execution_time.has_value() != d.period.has_value())
    ctx.fail(e, "resourcedemand", "executiontime and period go together: give both or neither");
  return d;
}

UsesDevice read_uses_device(ReadContext &ctx, const XmlElement &e) {
  UsesDevice u{e.attr("id"), e.attr("type"), detail::read_property_refs(ctx, &e), ctx.at(e)};
  return u;
}

CodeType read_code_type(const std::string &type) {
  if (type == "SharedLibrary")
    return CodeType::SharedLibrary;
  if (type == "KernelModule")
    return CodeType::KernelModule;
  if (type == "Driver")
    return CodeType::Driver;
  if (type == "Node")
    return CodeType::Node;
  return CodeType::Executable;
}

void read_dependency(ReadContext &ctx, const XmlElement &e, Implementation &impl) {
  for (const auto &c : e.children) {
    if (c.name == "softpkgref") {
      SoftPkgRef ref{detail::read_localfile(ctx, c), std::nullopt, {}, ctx.at(c)};
      if (const XmlElement *implref = c.child("implref")) {
        ref.implref = implref->attr("refid");
        ref.implref_where = ctx.at(*implref);
      }
      impl.softpkg_dependencies.push_back(std::move(ref));
    } else if (detail::is_property_ref(c.name)) {
      impl.property_dependencies.push_back({e.attr("type"), detail::read_property_ref(ctx, c)});
    }
  }
}

Implementation read_implementation(ReadContext &ctx, const XmlElement &e) {
  Implementation impl;
  impl.id = e.attr("id");
  impl.where = ctx.at(e);
  impl.description = e.child_text("description");
  for (const auto &c : e.children) {
    if (c.name == "propertyfile") {
      ctx.expect_type(c, "PRF");
      impl.property_file = detail::read_localfile(ctx, c);
    } else if (c.name == "code") {
      impl.code.type = read_code_type(c.attr("type"));
      impl.code.file = detail::read_localfile(ctx, c);
      impl.code.entrypoint = c.child_text("entrypoint");
      impl.code.stack_size = ctx.optional_child(c, "stacksize", parse_count);
      impl.code.priority = ctx.optional_child(c, "priority", parse_count);
    } else if (c.name == "compiler") {
      impl.compiler = {c.attr("name"), c.attr("version")};
    } else if (c.name == "programminglanguage") {
      impl.programming_language = c.attr("name");
    } else if (c.name == "humanlanguage") {
      impl.human_language = c.attr("name");
    } else if (c.name == "runtime") {
      impl.runtime = {c.attr("name"), c.attr("version")};
    } else if (c.name == "os" || c.name == "processor") {
      read_os_or_processor(ctx, c, impl);
    } else if (c.name == "dependency") {
      read_dependency(ctx, c, impl);
    } else if (c.name == "usesdevice") {
      impl.uses_devices.push_back(read_uses_device(ctx, c));
    } else if (c.name == "resourcedemand") {
      impl.resource_demand = read_resource_demand(ctx, c);
    }
  }
  return impl;
}

} // namespace

Expected<SoftPkg> read_spd(const XmlDocument &document) {
  ReadContext ctx(document);
  const XmlElement &root = document.root;
  SoftPkg spd;
  spd.file = document.file;
  spd.id = root.attr("id");
  spd.name = root.attr("name");
  spd.type = root.attr("type");
  spd.version = root.attr("version");
  spd.title = root.child_text("title");
  spd.description = root.child_text("description");
  std::set<std::string> impl_ids;
  for (const auto &c : root.children) {
    if (c.name == "author") {
      spd.authors.push_back(c.child_text("name"));
    } else if (c.name == "propertyfile") {
      ctx.expect_type(c, "PRF");
      spd.property_file = detail::read_localfile(ctx, c);
    } else if (c.name == "descriptor") {
      spd.descriptor = detail::read_localfile(ctx, c);
    } else if (c.name == "implementation") {
      spd.implementations.push_back(read_implementation(ctx, c));
      ctx.require_unique(impl_ids, spd.implementations.back().id, c, "implementation id");
    } else if (c.name == "usesdevice") {
      spd.uses_devices.push_back(read_uses_device(ctx, c));
    } else if (c.name == "child") {
      ctx.warn(c, "not-modelled",
               fmt::format("child package \"{}\" (REDHAWK 3's child devices) is read but not used",
                           c.attr("name")));
    }
  }
  if (spd.implementations.empty())
    ctx.warn(root, "no-implementation",
             fmt::format("softpkg \"{}\" has no implementation: nothing of it can run", spd.name));
  return detail::finish(ctx, std::move(spd));
}

} // namespace rsca::profile
