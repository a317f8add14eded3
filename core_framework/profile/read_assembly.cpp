// Readers of the parts SADs and DCDs share, and the checks of their internal references.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <map>

#include <fmt/ranges.h>

#include "common/content_filter.hpp"
#include "common/cpu_list.hpp"
#include "common/text.hpp"
#include "profile/connection_qos.hpp"
#include "profile/read_context.hpp"

namespace rsca::profile::detail {
namespace {

template <typename Enum, std::size_t N>
std::optional<Enum> enum_attr(ReadContext &ctx, const XmlElement &e, std::string_view name,
                              const std::pair<std::string_view, Enum> (&table)[N]) {
  const std::string *text = e.attribute(name);
  if (text == nullptr)
    return std::nullopt;
  for (const auto &[key, value] : table)
    if (key == *text)
      return value;
  // The schema enumerates these values; reaching here means schema and reader disagree.
  ctx.fail(e, "value", fmt::format("attribute {}: \"{}\" is not a known value", name, *text));
  return std::nullopt;
}

constexpr std::string_view kDeviceManagerRepId = "IDL:CF/DeviceManager:1.0";

template <typename Int>
tl::expected<Int, std::string> parse_int(std::string_view text) {
  Int value{};
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size())
    return tl::unexpected(fmt::format("\"{}\" is not a valid integer", text));
  return value;
}

constexpr std::pair<std::string_view, Criticality> kCriticality[] = {
    {"low", Criticality::Low},
    {"medium", Criticality::Medium},
    {"high", Criticality::High},
    {"safety", Criticality::Safety}};

SimpleRef read_simple_ref(ReadContext &ctx, const XmlElement &e) {
  return {e.attr("refid"), e.attr("value"), ctx.at(e)};
}

SimpleSequenceRef read_simple_sequence_ref(ReadContext &ctx, const XmlElement &e) {
  SimpleSequenceRef ref{e.attr("refid"), {}, ctx.at(e)};
  if (const XmlElement *values = e.child("values"))
    for (const auto &v : values->children)
      ref.values.push_back(v.text); // sequence values are not trimmed: strings keep their spaces
  return ref;
}

StructRef read_struct_members(ReadContext &ctx, const XmlElement &e, std::string refid) {
  StructRef ref{std::move(refid), {}, ctx.at(e)};
  for (const auto &c : e.children) {
    if (c.name == "simpleref")
      ref.members.emplace_back(read_simple_ref(ctx, c));
    else if (c.name == "simplesequenceref")
      ref.members.emplace_back(read_simple_sequence_ref(ctx, c));
  }
  return ref;
}

// The domainfinder types SCA 2.2.2 and REDHAWK define.
constexpr std::string_view kDomainFinderTypes[] = {"filemanager",   "log",         "eventchannel",
                                                   "namingservice", "servicename", "servicetype",
                                                   "domainmanager"};

FindBy read_findby(ReadContext &ctx, const XmlElement &e) {
  FindBy findby;
  if (const XmlElement *ns = e.child("namingservice")) {
    findby.kind = FindBy::Kind::NamingService;
    findby.name = ns->attr("name");
  } else if (const XmlElement *df = e.child("domainfinder")) {
    findby.kind = FindBy::Kind::DomainFinder;
    findby.type = df->attr("type");
    findby.name = df->attr("name");
    if (std::find(std::begin(kDomainFinderTypes), std::end(kDomainFinderTypes), findby.type) ==
        std::end(kDomainFinderTypes))
      ctx.warn(*df, "unknown-value",
               fmt::format("domainfinder type \"{}\" is none SCA or REDHAWK defines: a connection "
                           "through it cannot be made",
                           findby.type));
  } else if (const XmlElement *so = e.child("stringifiedobjectref")) {
    findby.kind = FindBy::Kind::StringifiedObjectRef;
    findby.name = so->trimmed_text();
  }
  return findby;
}

// The object an end of a connection names: one of the children of usesport, providesport or
// componentsupportedinterface.
EndpointTarget read_target(ReadContext &ctx, const XmlElement &end) {
  EndpointTarget target;
  for (const auto &c : end.children) {
    if (c.name != "usesidentifier" && c.name != "providesidentifier" &&
        c.name != "supportedidentifier")
      target.where = ctx.at(c);
    if (c.name == "componentinstantiationref") {
      target.kind = EndpointTarget::Kind::ComponentInstantiation;
      target.refid = c.attr("refid");
    } else if (c.name == "devicethatloadedthiscomponentref") {
      target.kind = EndpointTarget::Kind::DeviceThatLoadedThisComponent;
      target.refid = c.attr("refid");
    } else if (c.name == "deviceusedbythiscomponentref") {
      target.kind = EndpointTarget::Kind::DeviceUsedByThisComponent;
      target.refid = c.attr("refid");
      target.usesrefid = c.attr("usesrefid");
    } else if (c.name == "deviceusedbyapplication") {
      target.kind = EndpointTarget::Kind::DeviceUsedByApplication;
      target.usesrefid = c.attr("usesrefid");
    } else if (c.name == "findby") {
      target.kind = EndpointTarget::Kind::FindBy;
      target.findby = read_findby(ctx, c);
    }
  }
  return target;
}

// Every attribute by the one parser of QoS values (profile/connection_qos.hpp), which
// `rsca connect --qos` shares.
ConnectionQos read_qos(ReadContext &ctx, const XmlElement &e) {
  ConnectionQos qos;
  qos.where = ctx.at(e);
  for (std::string_view name : kQosAttributes)
    if (const std::string *text = e.attribute(name))
      if (auto set = set_qos_attribute(qos, name, *text); !set)
        ctx.fail(e, "value", fmt::format("attribute {}: \"{}\" is {}", name, *text, set.error()));
  if (auto why = qos_inconsistency(qos))
    ctx.fail(e, "qos", *why);
  return qos;
}

Timing read_timing(ReadContext &ctx, const XmlElement &e) {
  Timing timing;
  timing.where = ctx.at(e);
  timing.period = ctx.duration_attr(e, "period");
  timing.deadline = ctx.duration_attr(e, "deadline");
  timing.execution_time = ctx.duration_attr(e, "executiontime");
  timing.priority = ctx.optional_attr(e, "priority", parse_int<std::uint32_t>);
  timing.criticality = enum_attr(ctx, e, "criticality", kCriticality);
  auto finite = [](const std::optional<Duration> &d) { return d && !d->infinite(); };
  if (timing.execution_time && timing.execution_time->infinite() &&
      (finite(timing.deadline) || finite(timing.period)))
    ctx.fail(e, "timing", "executiontime is infinite: no finite deadline or period can be met");
  if (finite(timing.execution_time) && finite(timing.deadline) &&
      *timing.execution_time->value > *timing.deadline->value)
    ctx.fail(e, "timing", "executiontime is longer than the deadline: no schedule can meet it");
  if (finite(timing.execution_time) && finite(timing.period) &&
      *timing.execution_time->value > *timing.period->value)
    ctx.fail(e, "timing", "executiontime is longer than the period: utilization above 100%");
  return timing;
}

// REDHAWK reads any text as a start order; one that is no whole number orders nothing.
std::optional<std::uint32_t> read_start_order(ReadContext &ctx, const XmlElement &e) {
  const std::string *text = e.attribute("startorder");
  if (text == nullptr)
    return std::nullopt;
  auto order = parse_int<std::uint32_t>(trim(*text));
  if (!order)
    ctx.warn(e, "value",
             fmt::format("startorder \"{}\" is not a whole number: the instance has no start "
                         "order",
                         *text));
  return order ? std::optional(*order) : std::nullopt;
}

constexpr std::pair<std::string_view, ProcessorAffinity::Class> kAffinityClasses[] = {
    {"cpu", ProcessorAffinity::Class::Cpu},
    {"socket", ProcessorAffinity::Class::Socket},
    {"nic", ProcessorAffinity::Class::Nic},
    {"nice", ProcessorAffinity::Class::Nice}};

// Whether `value` is one the node can apply for `directive`; why not otherwise.
std::optional<std::string> affinity_value_problem(ProcessorAffinity::Class directive,
                                                  const std::string &value) {
  using Class = ProcessorAffinity::Class;
  if (directive == Class::Cpu || directive == Class::Socket) {
    auto list = parse_cpu_list(value);
    return list ? std::nullopt : std::optional(list.error());
  }
  if (directive == Class::Nice) {
    auto nice = parse_int<int>(trim(value));
    if (!nice || *nice < -20 || *nice > 19)
      return "a nice value is a whole number from -20 to 19";
    return std::nullopt;
  }
  if (trim(value).empty() || value.size() > 15) // IFNAMSIZ - 1
    return "a network interface name has 1 to 15 characters";
  return std::nullopt;
}

// REDHAWK's affinity: a directive class and its value, as simplerefs. What rsca cannot apply
// (a cgroup, REDHAWK's other affinity settings, a value out of form) is read with a warning.
std::optional<ProcessorAffinity> read_affinity(ReadContext &ctx, const XmlElement &e) {
  const XmlElement *directive_ref = nullptr;
  const XmlElement *value_ref = nullptr;
  for (const auto &c : e.children) {
    const std::string &refid = c.attr("refid");
    if (c.name == "simpleref" && refid == "affinity::exec_directive_class")
      directive_ref = &c;
    else if (c.name == "simpleref" && refid == "affinity::exec_directive_value")
      value_ref = &c;
    else
      ctx.warn(c, "unknown-value",
               fmt::format("affinity setting \"{}\" is not one rsca applies: ignored", refid));
  }
  if (directive_ref == nullptr || value_ref == nullptr) {
    ctx.warn(e, "affinity",
             "affinity needs affinity::exec_directive_class and affinity::exec_directive_value: "
             "ignored");
    return std::nullopt;
  }
  const std::string &name = directive_ref->attr("value");
  const auto *known = std::find_if(std::begin(kAffinityClasses), std::end(kAffinityClasses),
                                   [&](const auto &entry) { return entry.first == name; });
  if (known == std::end(kAffinityClasses)) {
    ctx.warn(*directive_ref, "unknown-value",
             fmt::format("affinity class \"{}\" is not one rsca applies (cpu, socket, nic, "
                         "nice): ignored",
                         name));
    return std::nullopt;
  }
  ProcessorAffinity affinity{known->second, std::string(trim(value_ref->attr("value"))), ctx.at(e)};
  if (auto problem = affinity_value_problem(affinity.directive, affinity.value)) {
    ctx.warn(*value_ref, "value",
             fmt::format("affinity {} \"{}\": {}: ignored", name, affinity.value, *problem));
    return std::nullopt;
  }
  return affinity;
}

// REDHAWK's level names, in DEBUG_LEVEL's order (0 is fatal).
constexpr std::string_view kLogLevels[] = {"FATAL", "ERROR", "WARN", "INFO", "DEBUG", "TRACE"};

LoggingConfig read_logging_config(ReadContext &ctx, const XmlElement &e) {
  LoggingConfig config{std::nullopt, e.trimmed_text(), ctx.at(e)};
  const std::string *level = e.attribute("level");
  if (level == nullptr)
    return config;
  std::string upper = *level;
  std::transform(upper.begin(), upper.end(), upper.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::toupper(ch)); });
  if (upper == "ALL")
    upper = "TRACE";
  for (std::size_t i = 0; i < std::size(kLogLevels); ++i)
    if (upper == kLogLevels[i])
      config.debug_level = static_cast<int>(i);
  if (!config.debug_level && upper != "OFF")
    ctx.warn(e, "unknown-value",
             fmt::format("log level \"{}\" is none of FATAL, ERROR, WARN, INFO, DEBUG, TRACE, "
                         "ALL, OFF: ignored",
                         *level));
  return config;
}

ComponentInstantiation read_instantiation(ReadContext &ctx, const XmlElement &e) {
  ComponentInstantiation ci;
  ci.id = e.attr("id");
  ci.where = ctx.at(e);
  ci.start_order = read_start_order(ctx, e);
  ci.usage_name = e.child_text("usagename");
  if (const XmlElement *affinity = e.child("affinity"))
    ci.affinity = read_affinity(ctx, *affinity);
  if (const XmlElement *logging = e.child("loggingconfig"))
    ci.logging = read_logging_config(ctx, *logging);
  ci.properties = read_property_refs(ctx, e.child("componentproperties"));
  for (const auto &c : e.children) {
    if (c.name == "findcomponent") {
      if (const XmlElement *ns = c.child("namingservice"))
        ci.naming_service_name = ns->attr("name");
    } else if (c.name == "devicerequires" || c.name == "deployerrequires") {
      for (const auto &r : c.children) {
        if (r.name == "requires")
          ci.device_requires.emplace_back(SimpleRef{r.attr("id"), r.attr("value"), ctx.at(r)});
        else if (is_property_ref(r.name))
          ci.device_requires.push_back(read_property_ref(ctx, r));
      }
    } else if (c.name == "timing") {
      ci.timing = read_timing(ctx, c);
    }
  }
  return ci;
}

std::string connection_label(const Connection &c) {
  return c.id.empty() ? std::string("connection") : fmt::format("connection \"{}\"", c.id);
}

} // namespace

LocalFile read_localfile(ReadContext &ctx, const XmlElement &holder) {
  const XmlElement *lf = holder.child("localfile");
  if (lf == nullptr)
    return {{}, ctx.at(holder)};
  return {lf->attr("name"), ctx.at(*lf)};
}

bool is_property_ref(std::string_view name) {
  return name == "simpleref" || name == "simplesequenceref" || name == "structref" ||
         name == "structsequenceref" || name == "propertyref";
}

PropertyRef read_property_ref(ReadContext &ctx, const XmlElement &e) {
  if (e.name == "simplesequenceref")
    return read_simple_sequence_ref(ctx, e);
  if (e.name == "structref")
    return read_struct_members(ctx, e, e.attr("refid"));
  if (e.name == "structsequenceref") {
    StructSequenceRef ref{e.attr("refid"), {}, ctx.at(e)};
    for (const auto &c : e.children)
      if (c.name == "structvalue")
        ref.values.push_back(read_struct_members(ctx, c, {}));
    return ref;
  }
  // simpleref, and SCA's propertyref (refid + value) in SPD dependencies.
  return read_simple_ref(ctx, e);
}

std::vector<PropertyRef> read_property_refs(ReadContext &ctx, const XmlElement *holder) {
  std::vector<PropertyRef> refs;
  if (holder == nullptr)
    return refs;
  for (const auto &c : holder->children)
    if (is_property_ref(c.name))
      refs.push_back(read_property_ref(ctx, c));
  return refs;
}

std::vector<ComponentFile> read_component_files(ReadContext &ctx, const XmlElement *holder) {
  std::vector<ComponentFile> files;
  if (holder == nullptr)
    return files;
  for (const auto &c : holder->children) {
    if (c.name != "componentfile")
      continue;
    ctx.expect_type(c, "SPD");
    files.push_back({c.attr("id"), c.attr("type"), read_localfile(ctx, c), ctx.at(c)});
  }
  return files;
}

ComponentPlacement read_component_placement(ReadContext &ctx, const XmlElement &e) {
  ComponentPlacement placement;
  for (const auto &c : e.children) {
    if (c.name == "componentfileref") {
      placement.componentfile_ref = c.attr("refid");
      placement.ref_where = ctx.at(c);
    } else if (c.name == "deployondevice") {
      placement.deploy_on_device = c.attr("refid");
    } else if (c.name == "compositepartofdevice") {
      placement.composite_part_of_device = c.attr("refid");
    } else if (c.name == "devicepkgfile") {
      ctx.expect_type(c, "DPD");
      placement.device_pkg_file = read_localfile(ctx, c);
    } else if (c.name == "componentinstantiation") {
      placement.instantiations.push_back(read_instantiation(ctx, c));
    }
  }
  return placement;
}

std::vector<Connection> read_connections(ReadContext &ctx, const XmlElement *holder) {
  std::vector<Connection> connections;
  if (holder == nullptr)
    return connections;
  for (const auto &e : holder->children) {
    Connection c;
    c.id = e.attr("id");
    c.where = ctx.at(e);
    for (const auto &part : e.children) {
      if (part.name == "usesport") {
        c.uses = {part.child_text("usesidentifier"), read_target(ctx, part), ctx.at(part)};
      } else if (part.name == "providesport") {
        c.provides = {ProvidesEnd::Kind::Port, part.child_text("providesidentifier"),
                      read_target(ctx, part), ctx.at(part)};
      } else if (part.name == "componentsupportedinterface") {
        c.provides = {ProvidesEnd::Kind::SupportedInterface, part.child_text("supportedidentifier"),
                      read_target(ctx, part), ctx.at(part)};
      } else if (part.name == "findby") {
        c.provides.kind = ProvidesEnd::Kind::FindBy;
        c.provides.target.kind = EndpointTarget::Kind::FindBy;
        c.provides.target.findby = read_findby(ctx, part);
        c.provides.target.where = ctx.at(part);
        c.provides.where = ctx.at(part);
      } else if (part.name == "qos") {
        c.qos = read_qos(ctx, part);
      } else if (part.name == "filter") {
        c.filter = part.trimmed_text();
        if (!c.subscribes_to_channel())
          ctx.fail(part, "filter",
                   fmt::format("{} has a filter but does not subscribe to an event channel "
                               "(usesport/findby/domainfinder type=\"eventchannel\")",
                               connection_label(c)));
        else if (auto parsed = ContentFilter::parse(*c.filter); !parsed)
          ctx.fail(part, "filter",
                   fmt::format("{}: the filter \"{}\" is not valid: {}", connection_label(c),
                               *c.filter, parsed.error()));
      }
    }
    connections.push_back(std::move(c));
  }
  return connections;
}

void check_assembly_references(ReadContext &ctx, const std::vector<ComponentFile> &files,
                               const std::vector<ComponentPlacement> &placements,
                               const std::vector<Connection> &connections) {
  std::set<std::string> file_ids;
  for (const auto &f : files)
    if (!file_ids.insert(f.id).second)
      ctx.report({f.where, "duplicate-id",
                  fmt::format("componentfile id \"{}\" is defined more than once", f.id)});

  std::set<std::string> instance_ids;
  for (const auto &p : placements) {
    if (file_ids.count(p.componentfile_ref) == 0)
      ctx.report({p.ref_where, "dangling-ref",
                  fmt::format("componentfileref refid \"{}\" names no componentfile (known: {})",
                              p.componentfile_ref, fmt::join(file_ids, ", "))});
    for (const auto &ci : p.instantiations)
      if (!instance_ids.insert(ci.id).second)
        ctx.report(
            {ci.where, "duplicate-id",
             fmt::format("componentinstantiation id \"{}\" is defined more than once", ci.id)});
  }

  auto check_target = [&](const EndpointTarget &t, const Connection &c) {
    if (t.kind == EndpointTarget::Kind::FindBy ||
        t.kind == EndpointTarget::Kind::DeviceUsedByApplication || instance_ids.count(t.refid) != 0)
      return;
    // REDHAWK resolves a DeviceManager's id here when the connection is to its interface.
    const bool device_manager = &t == &c.provides.target &&
                                c.provides.kind == ProvidesEnd::Kind::SupportedInterface &&
                                c.provides.port == kDeviceManagerRepId;
    Diagnostic d{t.where, "dangling-ref",
                 fmt::format("{} refers to componentinstantiation \"{}\", which this file does "
                             "not define",
                             connection_label(c), t.refid)};
    if (device_manager) {
      d.message += fmt::format(" (REDHAWK takes it for a DeviceManager; rsca's nodes do not "
                               "serve {}, so the connection cannot be made)",
                               kDeviceManagerRepId);
      ctx.warn_at(std::move(d));
      return;
    }
    ctx.report(std::move(d));
  };
  std::set<std::string> connection_ids;
  for (const auto &c : connections) {
    if (!c.id.empty() && !connection_ids.insert(c.id).second)
      ctx.report({c.where, "duplicate-id",
                  fmt::format("connectinterface id \"{}\" is defined more than once", c.id)});
    check_target(c.uses.target, c);
    check_target(c.provides.target, c);
    if (c.subscribes_to_channel() && c.publishes_to_channel())
      ctx.report({c.where, "connection",
                  fmt::format("{} joins two event channels; one end must be a component port",
                              connection_label(c))});
    if (c.qos && c.qos->transport == Transport::Tcp &&
        (c.subscribes_to_channel() || c.publishes_to_channel()))
      ctx.report({c.qos->where, "qos",
                  fmt::format("{}: transport=\"tcp\" is a stream between one uses port and one "
                              "provides port, not an event channel",
                              connection_label(c))});
  }
}

std::optional<Scalar> read_scalar(ReadContext &ctx, const XmlElement &e, TypeSpec spec,
                                  const std::string &text, std::string_view what) {
  auto value = parse_scalar(spec, text);
  if (!value) {
    ctx.fail(e, "value", fmt::format("{}: {}", what, value.error()));
    return std::nullopt;
  }
  return *value;
}

} // namespace rsca::profile::detail
