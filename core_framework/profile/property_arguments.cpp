#include "profile/property_arguments.hpp"

#include <fmt/format.h>

#include "profile/property_value_impl.hpp"

namespace rsca::profile {
namespace {

using detail::trim;
template <typename T>
using Parsed = tl::expected<T, std::string>;

// `text` split at its commas outside brackets, braces and quotes, each item trimmed. The nesting
// is only counted: how deep a value may go is the PRF's form, not the text's.
Parsed<std::vector<std::string_view>> split_items(std::string_view text) {
  std::vector<std::string_view> items;
  int depth = 0;
  bool quoted = false;
  std::size_t start = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        quoted = false;
    } else if (c == '"') {
      quoted = true;
    } else if (c == '[' || c == '{') {
      ++depth;
    } else if ((c == ']' || c == '}') && --depth < 0) {
      return tl::unexpected(fmt::format("an unmatched '{}'", c));
    } else if (c == ',' && depth == 0) {
      items.push_back(trim(text.substr(start, i - start)));
      start = i + 1;
    }
  }
  if (quoted)
    return tl::unexpected(std::string("an unterminated quote"));
  if (depth != 0)
    return tl::unexpected(std::string("an unclosed bracket or brace"));
  const auto last = trim(text.substr(start));
  if (!last.empty() || !items.empty())
    items.push_back(last);
  return items;
}

// An item as a value: a quoted one without its quotes and escapes; an unquoted one as it is,
// unless it holds what only a sequence or struct may.
Parsed<std::string> scalar_item(std::string_view item) {
  if (item.size() >= 2 && item.front() == '"' && item.back() == '"') {
    std::string out;
    for (std::size_t i = 1; i + 1 < item.size(); ++i)
      out += item[i] == '\\' && i + 2 < item.size() ? item[++i] : item[i];
    return out;
  }
  if (item.find_first_of("[]{}\"") != std::string_view::npos)
    return tl::unexpected(
        fmt::format("{} is not one value (quote it if it is: \"...\")", detail::quoted(item)));
  return std::string(item);
}

// The text inside `open`...`close`, when `text` is so enclosed.
std::optional<std::string_view> enclosed(std::string_view text, char open, char close) {
  text = trim(text);
  if (text.size() < 2 || text.front() != open || text.back() != close)
    return std::nullopt;
  return text.substr(1, text.size() - 2);
}

// [a,b,c] or a,b,c.
Parsed<std::vector<std::string>> sequence_items(std::string_view text) {
  auto items = split_items(enclosed(text, '[', ']').value_or(text));
  if (!items)
    return tl::unexpected(items.error());
  std::vector<std::string> values;
  for (auto item : *items) {
    auto value = scalar_item(item);
    if (!value)
      return tl::unexpected(value.error());
    values.push_back(std::move(*value));
  }
  return values;
}

Parsed<StructRef> struct_ref(const StructProperty &definition, std::string_view text) {
  const auto inside = enclosed(text, '{', '}');
  if (!inside)
    return tl::unexpected(
        fmt::format("{} is not a struct: give {{member=value,...}}", detail::quoted(trim(text))));
  auto items = split_items(*inside);
  if (!items)
    return tl::unexpected(items.error());
  StructRef ref{definition.id, {}, {}};
  for (auto item : *items) {
    const auto eq = item.find('=');
    if (eq == std::string_view::npos || eq == 0)
      return tl::unexpected(fmt::format("{} is not member=value", detail::quoted(item)));
    const std::string member(trim(item.substr(0, eq)));
    const auto value = trim(item.substr(eq + 1));
    const StructMember *found = definition.find_member(member);
    if (found != nullptr && std::holds_alternative<SimpleSequenceProperty>(*found)) {
      auto values = sequence_items(value);
      if (!values)
        return tl::unexpected(values.error());
      ref.members.emplace_back(SimpleSequenceRef{member, std::move(*values), {}});
      continue;
    }
    auto scalar = scalar_item(value);
    if (!scalar)
      return tl::unexpected(scalar.error());
    ref.members.emplace_back(SimpleRef{member, std::move(*scalar), {}}); // binding checks it
  }
  return ref;
}

Parsed<PropertyRef> struct_sequence_ref(const StructSequenceProperty &definition,
                                        std::string_view text) {
  const auto inside = enclosed(text, '[', ']');
  if (!inside)
    return tl::unexpected(
        fmt::format("{} is not a sequence of structs: give [{{member=value}},...]",
                    detail::quoted(trim(text))));
  auto items = split_items(*inside);
  if (!items)
    return tl::unexpected(items.error());
  StructSequenceRef ref{definition.id, {}, {}};
  for (auto item : *items) {
    auto one = struct_ref(definition.element, item);
    if (!one)
      return tl::unexpected(one.error());
    one->refid.clear();
    ref.values.push_back(std::move(*one));
  }
  return ref;
}

template <typename T>
Parsed<PropertyRef> widened(Parsed<T> ref) {
  if (!ref)
    return tl::unexpected(ref.error());
  return PropertyRef(std::move(*ref));
}

} // namespace

tl::expected<PropertyRef, std::string> ref_from_argument(const PropertyDefinition &definition,
                                                         std::string_view text) {
  const std::string &id = common_of(definition).id;
  Parsed<PropertyRef> ref = std::visit(
      [&](const auto &d) -> Parsed<PropertyRef> {
        using D = std::decay_t<decltype(d)>;
        if constexpr (std::is_same_v<D, SimpleProperty>) {
          return PropertyRef(SimpleRef{id, std::string(text), {}});
        } else if constexpr (std::is_same_v<D, SimpleSequenceProperty>) {
          auto values = sequence_items(text);
          if (!values)
            return tl::unexpected(values.error());
          return PropertyRef(SimpleSequenceRef{id, std::move(*values), {}});
        } else if constexpr (std::is_same_v<D, StructProperty>) {
          return widened(struct_ref(d, text));
        } else {
          return struct_sequence_ref(d, text);
        }
      },
      definition);
  if (!ref)
    return tl::unexpected(fmt::format("property \"{}\": {}", id, ref.error()));
  return ref;
}

} // namespace rsca::profile
