#include "common/content_filter.hpp"

#include <cctype>
#include <charconv>
#include <vector>

#include <fmt/format.h>

namespace rsca {

enum class Op : std::uint8_t { Eq, Ne, Lt, Le, Gt, Ge };

struct ContentFilter::Node {
  enum class Kind : std::uint8_t { And, Or, Not, Compare };
  Kind kind = Kind::Compare;
  std::vector<std::shared_ptr<const Node>> children; // And, Or: two or more; Not: one
  std::string field;                                 // Compare
  Op op = Op::Eq;
  FilterValue literal;
};

namespace {

using Node = ContentFilter::Node;
using NodePtr = std::shared_ptr<const Node>;

struct Token {
  enum class Kind : std::uint8_t { Name, Number, Text, Op, Open, Close, End };
  Kind kind = Kind::End;
  std::string text;
  double number = 0;
  std::size_t at = 0; // offset in the expression, for messages
};

class Parser {
public:
  explicit Parser(std::string_view text) : text_(text) {}

  tl::expected<NodePtr, std::string> parse() {
    if (auto failed = advance())
      return tl::unexpected(*failed);
    auto root = parse_or();
    if (!root)
      return root;
    if (token_.kind != Token::Kind::End)
      return error("and, or or the end of the filter");
    return root;
  }

private:
  tl::unexpected<std::string> error(std::string_view expected) const {
    return tl::unexpected(
        fmt::format("at column {}: expected {}, found {}", token_.at + 1, expected,
                    token_.kind == Token::Kind::End ? "the end" : "\"" + token_.text + "\""));
  }

  bool keyword(std::string_view word) const {
    if (token_.kind != Token::Kind::Name || token_.text.size() != word.size())
      return false;
    for (std::size_t i = 0; i < word.size(); ++i)
      if (std::tolower(static_cast<unsigned char>(token_.text[i])) != word[i])
        return false;
    return true;
  }

  // Reads the next token into token_; a message when the text holds something no token starts.
  std::optional<std::string> advance() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_])))
      ++pos_;
    token_ = Token{Token::Kind::End, "", 0, pos_};
    if (pos_ >= text_.size())
      return std::nullopt;
    const char c = text_[pos_];
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_')
      return take_while(Token::Kind::Name, [](char ch) {
        return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '.';
      });
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.')
      return take_number();
    if (c == '\'' || c == '"')
      return take_text(c);
    if (c == '(' || c == ')') {
      token_ = {c == '(' ? Token::Kind::Open : Token::Kind::Close, std::string(1, c), 0, pos_++};
      return std::nullopt;
    }
    // && || ! read as and, or, not (the C forms users also write).
    for (auto [symbol, word] : {std::pair{"&&", "and"}, std::pair{"||", "or"}})
      if (text_.substr(pos_, 2) == symbol) {
        token_ = {Token::Kind::Name, word, 0, pos_};
        pos_ += 2;
        return std::nullopt;
      }
    if (c == '!' && text_.substr(pos_, 2) != "!=") {
      token_ = {Token::Kind::Name, "not", 0, pos_++};
      return std::nullopt;
    }
    for (std::string_view op : {"==", "!=", "<>", "<=", ">=", "=", "<", ">"})
      if (text_.substr(pos_, op.size()) == op) {
        token_ = {Token::Kind::Op, std::string(op), 0, pos_};
        pos_ += op.size();
        return std::nullopt;
      }
    return fmt::format("at column {}: unexpected \"{}\"", pos_ + 1, c);
  }

  template <typename Pred>
  std::optional<std::string> take_while(Token::Kind kind, Pred pred) {
    const std::size_t start = pos_;
    while (pos_ < text_.size() && pred(text_[pos_]))
      ++pos_;
    token_ = {kind, std::string(text_.substr(start, pos_ - start)), 0, start};
    return std::nullopt;
  }

  std::optional<std::string> take_number() {
    const std::size_t start = pos_;
    std::size_t end = pos_ + 1;
    while (end < text_.size() && (std::isalnum(static_cast<unsigned char>(text_[end])) ||
                                  text_[end] == '.' || text_[end] == '+' || text_[end] == '-'))
      ++end;
    std::string_view word = text_.substr(start, end - start);
    if (word.front() == '+')
      word.remove_prefix(1);
    double value = 0;
    auto [ptr, ec] = std::from_chars(word.data(), word.data() + word.size(), value);
    if (ec != std::errc() || ptr != word.data() + word.size())
      return fmt::format("at column {}: \"{}\" is not a number", start + 1,
                         text_.substr(start, end - start));
    token_ = {Token::Kind::Number, std::string(text_.substr(start, end - start)), value, start};
    pos_ = end;
    return std::nullopt;
  }

  std::optional<std::string> take_text(char quote) {
    const std::size_t start = pos_;
    const auto close = text_.find(quote, pos_ + 1);
    if (close == std::string_view::npos)
      return fmt::format("at column {}: the text is not closed with {}", start + 1, quote);
    token_ = {Token::Kind::Text, std::string(text_.substr(start + 1, close - start - 1)), 0, start};
    pos_ = close + 1;
    return std::nullopt;
  }

  tl::expected<NodePtr, std::string> parse_or() { return parse_chain(Node::Kind::Or, "or"); }

  tl::expected<NodePtr, std::string> parse_and() { return parse_chain(Node::Kind::And, "and"); }

  // A chain of operands of `kind` joined by `word`: "a or b or c", "a and b".
  tl::expected<NodePtr, std::string> parse_chain(Node::Kind kind, std::string_view word) {
    auto operand = [&] { return kind == Node::Kind::Or ? parse_and() : parse_unary(); };
    auto first = operand();
    if (!first || !keyword(word))
      return first;
    auto node = std::make_shared<Node>();
    node->kind = kind;
    node->children.push_back(*first);
    while (keyword(word)) {
      if (auto failed = advance())
        return tl::unexpected(*failed);
      auto next = operand();
      if (!next)
        return next;
      node->children.push_back(*next);
    }
    return node;
  }

  tl::expected<NodePtr, std::string> parse_unary() {
    if (keyword("not")) {
      if (auto failed = advance())
        return tl::unexpected(*failed);
      auto operand = parse_unary();
      if (!operand)
        return operand;
      auto node = std::make_shared<Node>();
      node->kind = Node::Kind::Not;
      node->children.push_back(*operand);
      return node;
    }
    if (token_.kind == Token::Kind::Open) {
      if (auto failed = advance())
        return tl::unexpected(*failed);
      auto inner = parse_or();
      if (!inner)
        return inner;
      if (token_.kind != Token::Kind::Close)
        return error("\")\"");
      if (auto failed = advance())
        return tl::unexpected(*failed);
      return inner;
    }
    return parse_comparison();
  }

  tl::expected<NodePtr, std::string> parse_comparison() {
    if (token_.kind != Token::Kind::Name || keyword("and") || keyword("or"))
      return error("a field name");
    auto node = std::make_shared<Node>();
    node->field = token_.text;
    if (auto failed = advance())
      return tl::unexpected(*failed);
    if (token_.kind != Token::Kind::Op) {
      node->literal = true; // a bare field is a condition: it is true
      return node;
    }
    node->op = op_of(token_.text);
    if (auto failed = advance())
      return tl::unexpected(*failed);
    if (token_.kind == Token::Kind::Number)
      node->literal = token_.number;
    else if (token_.kind == Token::Kind::Text)
      node->literal = token_.text;
    else if (keyword("true") || keyword("false"))
      node->literal = keyword("true");
    else
      return error("a number, a 'text', true or false");
    if (auto failed = advance())
      return tl::unexpected(*failed);
    return node;
  }

  static Op op_of(std::string_view text) {
    if (text == "!=" || text == "<>")
      return Op::Ne;
    if (text == "<")
      return Op::Lt;
    if (text == "<=")
      return Op::Le;
    if (text == ">")
      return Op::Gt;
    if (text == ">=")
      return Op::Ge;
    return Op::Eq;
  }

  std::string_view text_;
  std::size_t pos_ = 0;
  Token token_;
};

template <typename T>
bool compare(const T &a, Op op, const T &b) {
  switch (op) {
  case Op::Eq:
    return a == b;
  case Op::Ne:
    return a != b;
  case Op::Lt:
    return a < b;
  case Op::Le:
    return a <= b;
  case Op::Gt:
    return a > b;
  case Op::Ge:
    return a >= b;
  }
  return false;
}

bool evaluate(const Node &node, const FieldLookup &fields) {
  switch (node.kind) {
  case Node::Kind::And:
    for (const auto &c : node.children)
      if (!evaluate(*c, fields))
        return false;
    return true;
  case Node::Kind::Or:
    for (const auto &c : node.children)
      if (evaluate(*c, fields))
        return true;
    return false;
  case Node::Kind::Not:
    return !evaluate(*node.children.front(), fields);
  case Node::Kind::Compare:
    break;
  }
  const auto value = fields(node.field);
  if (!value || value->index() != node.literal.index())
    return false;
  return std::visit(
      [&](const auto &v) {
        using V = std::decay_t<decltype(v)>;
        return compare(v, node.op, std::get<V>(node.literal));
      },
      *value);
}

} // namespace

tl::expected<ContentFilter, std::string> ContentFilter::parse(std::string_view expression) {
  auto root = Parser(expression).parse();
  if (!root)
    return tl::unexpected(root.error());
  return ContentFilter(std::string(expression), *root);
}

bool ContentFilter::matches(const FieldLookup &fields) const {
  return evaluate(*root_, fields);
}

} // namespace rsca
