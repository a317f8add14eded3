// Typed values of SCA properties (profile/property_value.hpp): the names of the types and
// actions, parsing dispatched by declared type (the parsers are in property_text.cpp,
// property_utctime.cpp and property_complex.cpp), printing, and the comparisons allocation
// properties use.
#include "profile/property_value.hpp"

#include <array>
#include <type_traits>
#include <utility>

#include "profile/property_value_impl.hpp"

namespace rsca::profile {

using namespace detail;

namespace {

using ScalarResult = tl::expected<Scalar, std::string>;

constexpr std::array<std::pair<SimpleType, std::string_view>, 14> kTypeNames{{
    {SimpleType::Boolean, "boolean"},
    {SimpleType::Char, "char"},
    {SimpleType::Octet, "octet"},
    {SimpleType::Short, "short"},
    {SimpleType::UShort, "ushort"},
    {SimpleType::Long, "long"},
    {SimpleType::ULong, "ulong"},
    {SimpleType::LongLong, "longlong"},
    {SimpleType::ULongLong, "ulonglong"},
    {SimpleType::Float, "float"},
    {SimpleType::Double, "double"},
    {SimpleType::String, "string"},
    {SimpleType::ObjRef, "objref"},
    {SimpleType::UtcTime, "utctime"},
}};

constexpr std::array<std::pair<Action, std::string_view>, 7> kActionNames{{
    {Action::Eq, "eq"},
    {Action::Ne, "ne"},
    {Action::Gt, "gt"},
    {Action::Lt, "lt"},
    {Action::Ge, "ge"},
    {Action::Le, "le"},
    {Action::External, "external"},
}};

template <class T>
ScalarResult to_scalar(tl::expected<T, std::string> parsed) {
  return std::move(parsed).map([](T value) { return Scalar{std::in_place_type<T>, value}; });
}

ScalarResult parse_simple(SimpleType type, std::string_view text) {
  switch (type) {
  case SimpleType::Boolean:
    return to_scalar(parse_boolean(text));
  case SimpleType::Char:
    return to_scalar(parse_char(text));
  case SimpleType::Octet:
    return to_scalar(parse_integer<std::uint8_t>(type, text));
  case SimpleType::Short:
    return to_scalar(parse_integer<std::int16_t>(type, text));
  case SimpleType::UShort:
    return to_scalar(parse_integer<std::uint16_t>(type, text));
  case SimpleType::Long:
    return to_scalar(parse_integer<std::int32_t>(type, text));
  case SimpleType::ULong:
    return to_scalar(parse_integer<std::uint32_t>(type, text));
  case SimpleType::LongLong:
    return to_scalar(parse_integer<std::int64_t>(type, text));
  case SimpleType::ULongLong:
    return to_scalar(parse_integer<std::uint64_t>(type, text));
  case SimpleType::Float:
    return to_scalar(parse_floating<float>(type, text));
  case SimpleType::Double:
    return to_scalar(parse_floating<double>(type, text));
  case SimpleType::String:
  case SimpleType::ObjRef:
    return Scalar{std::in_place_type<std::string>, text};
  case SimpleType::UtcTime:
    return to_scalar(parse_utctime(text));
  }
  return tl::unexpected(std::string("unknown simple type"));
}

struct Formatter {
  std::string operator()(bool value) const { return value ? "true" : "false"; }
  std::string operator()(char value) const { return std::string(1, value); }
  std::string operator()(const std::string &value) const { return value; }
  std::string operator()(const UtcTime &value) const { return format_utctime(value); }
  std::string operator()(const std::complex<double> &value) const { return format_complex(value); }
  template <class T>
  std::string operator()(T value) const {
    return number_text(value);
  }
};

template <class T>
constexpr bool kOrdered =
    std::is_arithmetic_v<T> && !std::is_same_v<T, bool> && !std::is_same_v<T, char>;

template <class T>
std::optional<bool> compare(Action action, const T &device, const T &requested) {
  switch (action) {
  case Action::Eq:
    return device == requested;
  case Action::Ne:
    return device != requested;
  default:
    break;
  }
  if constexpr (kOrdered<T>) {
    switch (action) {
    case Action::Gt:
      return device > requested;
    case Action::Lt:
      return device < requested;
    case Action::Ge:
      return device >= requested;
    case Action::Le:
      return device <= requested;
    default:
      break;
    }
  }
  return std::nullopt;
}

} // namespace

std::optional<SimpleType> simple_type_from_name(std::string_view name) {
  for (const auto &[type, type_text] : kTypeNames) {
    if (type_text == name)
      return type;
  }
  return std::nullopt;
}

std::string_view to_string(SimpleType type) {
  for (const auto &[candidate, name] : kTypeNames) {
    if (candidate == type)
      return name;
  }
  return "unknown";
}

bool is_integer(SimpleType type) {
  switch (type) {
  case SimpleType::Octet:
  case SimpleType::Short:
  case SimpleType::UShort:
  case SimpleType::Long:
  case SimpleType::ULong:
  case SimpleType::LongLong:
  case SimpleType::ULongLong:
    return true;
  default:
    return false;
  }
}

bool is_floating(SimpleType type) {
  return type == SimpleType::Float || type == SimpleType::Double;
}

bool is_numeric(SimpleType type) {
  return is_integer(type) || is_floating(type);
}

std::optional<Action> action_from_name(std::string_view name) {
  for (const auto &[action, action_text] : kActionNames) {
    if (action_text == name)
      return action;
  }
  return std::nullopt;
}

std::string_view to_string(Action action) {
  for (const auto &[candidate, name] : kActionNames) {
    if (candidate == action)
      return name;
  }
  return "unknown";
}

tl::expected<Scalar, std::string> parse_scalar(TypeSpec spec, std::string_view text) {
  const bool textual = spec.type == SimpleType::String || spec.type == SimpleType::ObjRef;
  if (spec.complex)
    return parse_complex(spec.type, trim(text));
  if (textual)
    return Scalar{std::in_place_type<std::string>, text};
  // A lone character is taken as it is, so that char can hold a space.
  if (spec.type == SimpleType::Char && text.size() == 1)
    return Scalar{std::in_place_type<char>, text.front()};
  return parse_simple(spec.type, trim(text));
}

std::string format_scalar(const Scalar &value) {
  return std::visit(Formatter{}, value);
}

std::optional<bool> satisfies(Action action, const Scalar &device_value, const Scalar &requested) {
  if (action == Action::External || device_value.index() != requested.index())
    return std::nullopt;
  return std::visit(
      [&](const auto &device) {
        using T = std::decay_t<decltype(device)>;
        return compare<T>(action, device, std::get<T>(requested));
      },
      device_value);
}

} // namespace rsca::profile
