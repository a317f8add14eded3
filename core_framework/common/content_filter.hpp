// A subscriber's content filter (the SAD's <filter>, notification-service style): only events
// that match it are delivered to the component. The publisher knows nothing of it.
//
//   filter     := or
//   or         := and (("or" | "||") and)*
//   and        := unary (("and" | "&&") unary)*
//   unary      := ("not" | "!") unary | "(" or ")" | comparison
//   comparison := field op literal | field       (a bare field: the field is true)
//   field      := name ("." name)*            e.g. range, value.distance, source
//   op         := "=" | "==" | "!=" | "<>" | "<" | "<=" | ">" | ">="
//   literal    := number | 'text' | "text" | true | false
//
// A field an event does not have makes its comparison false (as SQL's unknown), and so does a
// comparison between a number and a text.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

#include <tl/expected.hpp>

namespace rsca {

using FilterValue = std::variant<double, std::string, bool>;
// The value of a field of the event being filtered, or nothing when it has no such field.
using FieldLookup = std::function<std::optional<FilterValue>(std::string_view field)>;

class ContentFilter {
public:
  // Parses `expression`; an error says where and what was expected.
  static tl::expected<ContentFilter, std::string> parse(std::string_view expression);

  bool matches(const FieldLookup &fields) const;
  const std::string &expression() const { return expression_; }

  struct Node;

private:
  ContentFilter(std::string expression, std::shared_ptr<const Node> root)
      : expression_(std::move(expression)), root_(std::move(root)) {}

  std::string expression_;
  std::shared_ptr<const Node> root_;
};

} // namespace rsca
