// PRF reader: property definitions with typed defaults, checked within the file.
#include "profile/read_context.hpp"

namespace rsca::profile {
namespace {

using detail::ReadContext;

// The schema admits only the three names; none given is SCA's default, readwrite.
AccessMode read_mode(const XmlElement &e) {
  return access_mode_from_name(e.attr("mode")).value_or(AccessMode::ReadWrite);
}

void read_common(ReadContext &ctx, const XmlElement &e, PropertyCommon &p) {
  p.id = e.attr("id");
  p.name = e.attr("name");
  p.mode = read_mode(e);
  p.description = e.child_text("description");
  p.where = ctx.at(e);
  for (const auto &c : e.children) {
    if (c.name != "kind" && c.name != "configurationkind")
      continue;
    if (auto kind = property_kind_from_name(c.attr("kindtype")))
      p.kinds.push_back(*kind);
    else
      ctx.warn(c, "unknown-value",
               fmt::format("kindtype \"{}\" is no property kind (allocation, property, configure, "
                           "test, execparam, factoryparam, event, message): ignored",
                           c.attr("kindtype")));
  }
}

TypeSpec read_type(const XmlElement &e) {
  TypeSpec spec;
  spec.type = simple_type_from_name(e.attr("type")).value_or(SimpleType::String);
  spec.complex = e.attr("complex") == "true";
  return spec;
}

std::optional<Action> read_action(const XmlElement &e) {
  const XmlElement *a = e.child("action");
  return a != nullptr ? action_from_name(a->attr("type")) : std::nullopt;
}

bool in_range(const Scalar &value, const ValueRange &range) {
  return satisfies(Action::Ge, value, range.min).value_or(true) &&
         satisfies(Action::Le, value, range.max).value_or(true);
}

std::optional<ValueRange> read_range(ReadContext &ctx, const XmlElement &e, TypeSpec spec,
                                     const std::string &id) {
  const XmlElement *r = e.child("range");
  if (r == nullptr)
    return std::nullopt;
  auto min =
      detail::read_scalar(ctx, *r, spec, r->attr("min"), fmt::format("range min of \"{}\"", id));
  auto max =
      detail::read_scalar(ctx, *r, spec, r->attr("max"), fmt::format("range max of \"{}\"", id));
  if (!min || !max)
    return std::nullopt;
  if (satisfies(Action::Gt, *min, *max).value_or(false)) {
    ctx.fail(*r, "range",
             fmt::format("range of \"{}\" is empty: min {} is above max {}", id,
                         format_scalar(*min), format_scalar(*max)));
    return std::nullopt;
  }
  return ValueRange{*min, *max};
}

void check_in_range(ReadContext &ctx, const XmlElement &e, const std::optional<ValueRange> &range,
                    const Scalar &value, const std::string &id) {
  if (range && !in_range(value, *range))
    ctx.fail(e, "range",
             fmt::format("value {} of \"{}\" is outside its range {}..{}", format_scalar(value), id,
                         format_scalar(range->min), format_scalar(range->max)));
}

SimpleProperty read_simple(ReadContext &ctx, const XmlElement &e) {
  SimpleProperty p;
  read_common(ctx, e, p);
  p.type = read_type(e);
  p.units = e.child_text("units");
  p.action = read_action(e);
  p.commandline = e.attr("commandline") == "true";
  p.optional = e.attr("optional") == "true";
  p.range = read_range(ctx, e, p.type, p.id);
  if (const XmlElement *v = e.child("value")) {
    // Strings keep their spaces; other types are trimmed by the value parser.
    p.value = detail::read_scalar(ctx, *v, p.type, v->text, fmt::format("value of \"{}\"", p.id));
    if (p.value)
      check_in_range(ctx, *v, p.range, *p.value, p.id);
  }
  if (const XmlElement *enums = e.child("enumerations")) {
    for (const auto &en : enums->children) {
      const std::string *text = en.attribute("value");
      if (text == nullptr)
        continue; // a label without a value documents the value itself
      auto value =
          detail::read_scalar(ctx, en, p.type, *text,
                              fmt::format("enumeration \"{}\" of \"{}\"", en.attr("label"), p.id));
      if (value)
        p.enumerations.push_back({en.attr("label"), *value});
    }
  }
  return p;
}

SimpleSequenceProperty read_simple_sequence(ReadContext &ctx, const XmlElement &e) {
  SimpleSequenceProperty p;
  read_common(ctx, e, p);
  p.type = read_type(e);
  p.units = e.child_text("units");
  p.action = read_action(e);
  p.optional = e.attr("optional") == "true";
  p.range = read_range(ctx, e, p.type, p.id);
  if (const XmlElement *values = e.child("values")) {
    p.values.emplace();
    for (const auto &v : values->children) {
      auto value =
          detail::read_scalar(ctx, v, p.type, v.text, fmt::format("value of \"{}\"", p.id));
      if (!value)
        continue;
      check_in_range(ctx, v, p.range, *value, p.id);
      p.values->push_back(*value);
    }
  }
  return p;
}

// A <structvalue> (or a struct's member defaults) typed against the struct's members.
StructValue read_struct_value(ReadContext &ctx, const XmlElement &e, const StructProperty &def) {
  StructValue value;
  for (const auto &c : e.children) {
    if (c.name != "simpleref" && c.name != "simplesequenceref")
      continue;
    const std::string &refid = c.attr("refid");
    const StructMember *member = def.find_member(refid);
    if (member == nullptr) {
      ctx.fail(c, "unknown-property",
               fmt::format("struct \"{}\" has no member \"{}\"", def.id, refid));
      continue;
    }
    if (const auto *simple = std::get_if<SimpleProperty>(member)) {
      if (auto v = detail::read_scalar(ctx, c, simple->type, c.attr("value"),
                                       fmt::format("value of \"{}\"", refid)))
        value.members.emplace_back(refid, *v);
      continue;
    }
    const auto &sequence = std::get<SimpleSequenceProperty>(*member);
    std::vector<Scalar> items;
    if (const XmlElement *values = c.child("values"))
      for (const auto &v : values->children)
        if (auto item = detail::read_scalar(ctx, v, sequence.type, v.text,
                                            fmt::format("value of \"{}\"", refid)))
          items.push_back(*item);
    value.members.emplace_back(refid, std::move(items));
  }
  return value;
}

StructProperty read_struct(ReadContext &ctx, const XmlElement &e) {
  StructProperty p;
  read_common(ctx, e, p);
  std::set<std::string> member_ids;
  StructValue defaults;
  for (const auto &c : e.children) {
    if (c.name == "simple") {
      p.members.emplace_back(read_simple(ctx, c));
    } else if (c.name == "simplesequence") {
      p.members.emplace_back(read_simple_sequence(ctx, c));
    } else {
      continue;
    }
    const PropertyCommon &member = common_of(p.members.back());
    ctx.require_unique(member_ids, member.id, c, fmt::format("member of struct \"{}\"", p.id));
    if (const auto *simple = std::get_if<SimpleProperty>(&p.members.back());
        simple && simple->value)
      defaults.members.emplace_back(member.id, *simple->value);
    if (const auto *seq = std::get_if<SimpleSequenceProperty>(&p.members.back());
        seq && seq->values)
      defaults.members.emplace_back(member.id, *seq->values);
  }
  if (!defaults.members.empty())
    p.value = std::move(defaults);
  return p;
}

StructSequenceProperty read_struct_sequence(ReadContext &ctx, const XmlElement &e) {
  StructSequenceProperty p;
  read_common(ctx, e, p);
  if (const XmlElement *element = e.child("struct"))
    p.element = read_struct(ctx, *element);
  for (const auto &c : e.children)
    if (c.name == "structvalue")
      p.values.push_back(read_struct_value(ctx, c, p.element));
  return p;
}

} // namespace

Expected<Properties> read_prf(const XmlDocument &document) {
  ReadContext ctx(document);
  Properties prf;
  prf.file = document.file;
  std::set<std::string> ids;
  for (const auto &e : document.root.children) {
    if (e.name == "simple")
      prf.properties.emplace_back(read_simple(ctx, e));
    else if (e.name == "simplesequence")
      prf.properties.emplace_back(read_simple_sequence(ctx, e));
    else if (e.name == "struct")
      prf.properties.emplace_back(read_struct(ctx, e));
    else if (e.name == "structsequence")
      prf.properties.emplace_back(read_struct_sequence(ctx, e));
    else
      continue;
    ctx.require_unique(ids, common_of(prf.properties.back()).id, e, "property id");
  }
  return detail::finish(ctx, std::move(prf));
}

} // namespace rsca::profile
