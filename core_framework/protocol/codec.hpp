// How the typed messages of the wire protocol become JSON and back, strictly.
//
// A message is a plain struct that lists its fields once, in a static `fields()`:
//
//   struct TerminateRequest {
//     std::int64_t pid = 0;
//     static constexpr auto fields() { return std::tuple{required("pid", &TerminateRequest::pid)};
//     }
//   };
//
// encode() writes every field (an empty optional is left out); decode() reads a JSON object
// into the struct and refuses, with a message naming the field, a missing required field, a
// value of the wrong type or out of range, and a field the message does not have: a request from
// the network is untrusted, and a typo in a field name is a bug to see, not a value to ignore.
// Field types: bool, integers, double, std::string, Json (free-form), Bytes, enums with an
// EnumNames table, nested messages, and std::vector, std::optional and std::map<std::string, T>
// of them.
//
// A message may also say what its fields alone cannot (a bound, a range) in a `check()`, which
// decode() runs on the message read (checked() below).
//
// Every string, list and map read is bounded: kMaxStringBytes and kMaxItems unless its field says
// otherwise (`required("content", &F::content).at_most(n)`, for the field's own value). A request
// of half a million entries was kept whole before its handler saw it (issue 37, defect 8); the
// body as a whole is bounded where it arrives (protocol/json_text.hpp).
//
// Bytes are a JSON binary value: never text. The one field of a reply named kPayloadField may
// hold them; the control plane carries it beside the reply's JSON (control.idl, Reply.payload).
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tl/expected.hpp>

namespace rsca::protocol {

using Json = nlohmann::json;
using Bytes = Json::binary_t;

// The member of a reply whose bytes travel beside its JSON (see above).
inline constexpr const char *kPayloadField = "payload";

// What was wrong with a message, and where: path "connections[2].port", what "expected a
// string, found number".
struct DecodeError {
  std::string path;
  std::string what;
  std::string to_string() const {
    return path.empty() ? what : fmt::format("field \"{}\": {}", path, what);
  }
  // The same error seen from the value that holds this one at `step` ("port" or "[2]").
  DecodeError within(std::string_view step) const {
    const bool index = !path.empty() && path.front() == '[';
    return {fmt::format("{}{}{}", step, path.empty() || index ? "" : ".", path), what};
  }
};
using DecodeResult = tl::expected<void, DecodeError>;

// What a field may hold at most, when it does not say: bytes of a string, items of a list or map.
inline constexpr std::size_t kMaxStringBytes = 1U << 20U;
inline constexpr std::size_t kMaxItems = 1U << 16U;

template <typename Message, typename T>
struct Field {
  std::string_view key;
  T Message::*member;
  bool required;
  std::size_t most = 0; // of the string's bytes or the list's items; 0: the default above
  // The same field, holding at most `n` (bytes of a string, items of a list or map).
  constexpr Field at_most(std::size_t n) const {
    Field bounded = *this;
    bounded.most = n;
    return bounded;
  }
};

template <typename Message, typename T>
constexpr Field<Message, T> required(std::string_view key, T Message::*member) {
  return {key, member, true};
}

// Absent: the member keeps its default (an std::optional stays empty).
template <typename Message, typename T>
constexpr Field<Message, T> optional(std::string_view key, T Message::*member) {
  return {key, member, false};
}

// A message with no fields.
struct Empty {
  static constexpr auto fields() { return std::tuple{}; }
  bool operator==(const Empty &) const = default;
};

// An enum travels as its name: specialise with `static constexpr std::array names{std::pair{
// E::A, "a"}, ...}`.
template <typename E>
struct EnumNames;

template <typename T>
concept MessageType = requires {
  T::fields();
};

template <typename E>
concept NamedEnum = std::is_enum_v<E> && requires {
  EnumNames<E>::names;
};

template <typename E>
requires NamedEnum<E> std::string_view enum_name(E value) {
  for (const auto &[v, name] : EnumNames<E>::names)
    if (v == value)
      return name;
  return "?";
}

template <typename E>
requires NamedEnum<E> std::optional<E> enum_value(std::string_view name) {
  for (const auto &[v, n] : EnumNames<E>::names)
    if (n == name)
      return v;
  return std::nullopt;
}

namespace detail {

template <typename T>
struct IsOptional : std::false_type {};
template <typename T>
struct IsOptional<std::optional<T>> : std::true_type {};
template <typename T>
struct IsVector : std::false_type {};
template <typename T>
struct IsVector<std::vector<T>> : std::true_type {};
template <typename T>
struct IsStringMap : std::false_type {};
template <typename T>
struct IsStringMap<std::map<std::string, T>> : std::true_type {};

inline std::string found(const Json &j) {
  return j.is_null() ? "null" : std::string(j.type_name());
}

inline tl::unexpected<DecodeError> wrong(const Json &j, std::string_view expected) {
  return tl::unexpected(DecodeError{{}, fmt::format("expected {}, found {}", expected, found(j))});
}

inline tl::unexpected<DecodeError> invalid(std::string what) {
  return tl::unexpected(DecodeError{{}, std::move(what)});
}

// Refused when `size` is over `most` (0: `otherwise`).
inline DecodeResult bounded(std::size_t size, std::size_t most, std::size_t otherwise,
                            std::string_view unit) {
  const std::size_t bound = most != 0 ? most : otherwise;
  if (size > bound)
    return invalid(fmt::format("{} {}, over the limit of {}", size, unit, bound));
  return {};
}

} // namespace detail

template <typename T>
Json encode(const T &value);
// `most`: the bound of a string's bytes or a list's items (0: kMaxStringBytes, kMaxItems).
template <typename T>
DecodeResult decode_into(const Json &json, T &out, std::size_t most = 0);

template <MessageType M>
Json encode_message(const M &message) {
  Json out = Json::object();
  std::apply(
      [&](const auto &...field) {
        (
            [&] {
              const auto &value = message.*(field.member);
              using V = std::decay_t<decltype(value)>;
              if constexpr (detail::IsOptional<V>::value) {
                if (value)
                  out[std::string(field.key)] = encode(*value);
              } else {
                out[std::string(field.key)] = encode(value);
              }
            }(),
            ...);
      },
      M::fields());
  return out;
}

// What a message's fields alone do not say (a bound on a list's size, a number's range): a message
// with `std::optional<DecodeError> check() const` is refused when it finds something.
template <MessageType M>
DecodeResult checked(const M &message) {
  if constexpr (requires { message.check(); }) {
    if (auto wrong = message.check())
      return tl::unexpected(std::move(*wrong));
  }
  return {};
}

template <MessageType M>
DecodeResult decode_message(const Json &json, M &out) {
  if (!json.is_object())
    return detail::wrong(json, "an object");
  DecodeResult result;
  std::size_t known = 0;
  std::apply(
      [&](const auto &...field) {
        (
            [&] {
              if (!result)
                return;
              auto it = json.find(field.key);
              if (it == json.end()) {
                if (field.required)
                  result = detail::invalid(fmt::format("missing field \"{}\"", field.key));
                return;
              }
              ++known;
              if (auto ok = decode_into(*it, out.*(field.member), field.most); !ok)
                result = tl::unexpected(ok.error().within(field.key));
            }(),
            ...);
      },
      M::fields());
  if (result && known == json.size())
    return checked(out);
  if (!result)
    return result;
  for (const auto &[key, value] : json.items()) {
    bool listed = false;
    std::apply([&](const auto &...field) { ((listed = listed || field.key == key), ...); },
               M::fields());
    if (!listed)
      return detail::invalid(fmt::format("unknown field \"{}\"", key));
  }
  return checked(out);
}

template <typename T>
Json encode(const T &value) {
  if constexpr (MessageType<T>) {
    return encode_message(value);
  } else if constexpr (std::is_same_v<T, Bytes>) {
    return Json::binary(static_cast<const Bytes::container_type &>(value));
  } else if constexpr (NamedEnum<T>) {
    return std::string(enum_name(value));
  } else if constexpr (detail::IsOptional<T>::value) {
    return value ? encode(*value) : Json();
  } else if constexpr (detail::IsVector<T>::value) {
    Json out = Json::array();
    for (const auto &item : value)
      out.push_back(encode(item));
    return out;
  } else if constexpr (detail::IsStringMap<T>::value) {
    Json out = Json::object();
    for (const auto &[key, item] : value)
      out[key] = encode(item);
    return out;
  } else {
    return Json(value);
  }
}

template <typename T>
DecodeResult decode_into(const Json &json, T &out, std::size_t most) {
  if constexpr (MessageType<T>) {
    return decode_message(json, out);
  } else if constexpr (std::is_same_v<T, Json>) {
    out = json;
    return {};
  } else if constexpr (std::is_same_v<T, Bytes>) {
    if (!json.is_binary())
      return detail::wrong(json, "bytes");
    out = json.get_binary();
    return {};
  } else if constexpr (std::is_same_v<T, bool>) {
    if (!json.is_boolean())
      return detail::wrong(json, "true or false");
    out = json.get<bool>();
    return {};
  } else if constexpr (std::is_integral_v<T>) {
    if (json.is_number_unsigned()) {
      const auto v = json.get<std::uint64_t>();
      if (v > static_cast<std::uint64_t>(std::numeric_limits<T>::max()))
        return detail::invalid(fmt::format("{} is out of range", v));
      out = static_cast<T>(v);
      return {};
    }
    if (!json.is_number_integer())
      return detail::wrong(json, "an integer");
    const auto v = json.get<std::int64_t>();
    if constexpr (std::is_unsigned_v<T>) {
      if (v < 0)
        return detail::invalid(fmt::format("{} is out of range", v));
    } else if (v < std::numeric_limits<T>::min() || v > std::numeric_limits<T>::max()) {
      return detail::invalid(fmt::format("{} is out of range", v));
    }
    out = static_cast<T>(v);
    return {};
  } else if constexpr (std::is_floating_point_v<T>) {
    if (!json.is_number())
      return detail::wrong(json, "a number");
    out = json.get<T>();
    return {};
  } else if constexpr (std::is_same_v<T, std::string>) {
    if (!json.is_string())
      return detail::wrong(json, "a string");
    const auto &text = json.get_ref<const std::string &>();
    if (auto ok = detail::bounded(text.size(), most, kMaxStringBytes, "bytes"); !ok)
      return ok;
    out = text;
    return {};
  } else if constexpr (NamedEnum<T>) {
    if (!json.is_string())
      return detail::wrong(json, "a string");
    auto value = enum_value<T>(json.get_ref<const std::string &>());
    if (!value)
      return detail::invalid(
          fmt::format("\"{}\" is not one of the names allowed", json.get<std::string>()));
    out = *value;
    return {};
  } else if constexpr (detail::IsOptional<T>::value) {
    typename T::value_type inner{};
    if (auto ok = decode_into(json, inner, most); !ok)
      return ok;
    out = std::move(inner);
    return {};
  } else if constexpr (detail::IsVector<T>::value) {
    if (!json.is_array())
      return detail::wrong(json, "an array");
    if (auto ok = detail::bounded(json.size(), most, kMaxItems, "items"); !ok)
      return ok;
    out.clear();
    out.reserve(json.size());
    for (std::size_t i = 0; i < json.size(); ++i) {
      typename T::value_type item{};
      if (auto ok = decode_into(json[i], item); !ok)
        return tl::unexpected(ok.error().within(fmt::format("[{}]", i)));
      out.push_back(std::move(item));
    }
    return {};
  } else if constexpr (detail::IsStringMap<T>::value) {
    if (!json.is_object())
      return detail::wrong(json, "an object");
    if (auto ok = detail::bounded(json.size(), most, kMaxItems, "entries"); !ok)
      return ok;
    out.clear();
    for (const auto &[key, item] : json.items()) {
      if (auto ok = detail::bounded(key.size(), 0, kMaxStringBytes, "bytes in a key"); !ok)
        return ok;
      typename T::mapped_type value{};
      if (auto ok = decode_into(item, value); !ok)
        return tl::unexpected(ok.error().within(fmt::format("[\"{}\"]", key)));
      out.emplace(key, std::move(value));
    }
    return {};
  } else {
    static_assert(sizeof(T) == 0, "no wire form for this type");
  }
}

// Reads a whole message: its value, or what is wrong with it.
template <MessageType M>
tl::expected<M, std::string> decode(const Json &json) {
  M message{};
  if (auto ok = decode_message(json, message); !ok)
    return tl::unexpected(ok.error().to_string());
  return message;
}

} // namespace rsca::protocol
