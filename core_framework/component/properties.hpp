// A component's properties: the PRF definitions, the member variables the component binds to
// them, and the values of the ones it leaves unbound. configure checks every value against the
// PRF before it applies any; query reads them back as JSON (profile/property_json.hpp).
//
// Bindings are typed: a variable of a C++ type holds one PRF type.
//   bool: boolean; char: char; std::uint8_t: octet; std::int16_t: short; std::uint16_t: ushort;
//   std::int32_t: long; std::uint32_t: ulong; std::int64_t: longlong; std::uint64_t: ulonglong;
//   float: float; double: double; std::string: string or objref; profile::UtcTime: utctime;
//   std::complex<double>: any complex type.
// std::vector of these binds a simplesequence; std::atomic of an arithmetic one binds a simple
// that other threads read without a lock; a struct of the component's own binds a struct (and a
// std::vector of it a structsequence) through a list of fields.
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/diagnostic.hpp"
#include "control/endpoint.hpp"
#include "profile/prf.hpp"

namespace rsca::component {

// Called after a configure applied a property (every configure of it, changed or not), with the
// value before and after.
template <typename T>
using ChangeCallback = std::function<void(const T &old_value, const T &new_value)>;

namespace detail {

template <typename T>
inline constexpr bool kIsScalar = std::is_constructible_v<profile::Scalar, std::in_place_type_t<T>>;

// The index in profile::Scalar of a C++ type.
template <typename T>
std::size_t scalar_index() {
  static_assert(kIsScalar<T>, "not a property type: see component/properties.hpp");
  return profile::Scalar(std::in_place_type<T>).index();
}

// Why a variable of the scalar type at `index` cannot bind `definition` (simple or sequence).
std::optional<std::string> simple_mismatch(const profile::PropertyDefinition &definition,
                                           std::size_t index, bool sequence);
std::optional<std::string> member_mismatch(const profile::StructMember &member, std::size_t index,
                                           bool sequence);

template <typename T>
profile::Scalar to_scalar(const T &value) {
  return profile::Scalar(std::in_place_type<T>, value);
}

template <typename T>
std::vector<profile::Scalar> to_scalars(const std::vector<T> &values) {
  std::vector<profile::Scalar> out;
  out.reserve(values.size());
  for (const auto &v : values)
    out.push_back(to_scalar(v));
  return out;
}

template <typename T>
std::vector<T> from_scalars(const std::vector<profile::Scalar> &values) {
  std::vector<T> out;
  out.reserve(values.size());
  for (const auto &v : values)
    out.push_back(std::get<T>(v));
  return out;
}

template <typename T>
std::function<void()> notification(const ChangeCallback<T> &callback, T old_value, T new_value) {
  if (!callback)
    return {};
  return [callback, old_value = std::move(old_value), new_value = std::move(new_value)] {
    callback(old_value, new_value);
  };
}

} // namespace detail

// The variable behind one property.
class PropertyBinding {
public:
  virtual ~PropertyBinding() = default;
  // Why the variable cannot hold values of `definition`; empty when it can.
  virtual std::optional<std::string>
  mismatch(const profile::PropertyDefinition &definition) const = 0;
  virtual profile::PropertyValue get() const = 0;
  // `value` fits the definition (from_json checked it). Returns the change notification to run
  // once every value of the configure is applied (empty when there is no callback).
  virtual std::function<void()> set(const profile::PropertyValue &value) = 0;
};

// One field of a struct S bound to a member of a struct property.
template <typename S>
class Field {
public:
  template <typename M>
  Field(std::string id, M S::*member) : id_(std::move(id)) {
    if constexpr (detail::kIsScalar<M>) {
      mismatch_ = [](const profile::StructMember &m) {
        return detail::member_mismatch(m, detail::scalar_index<M>(), false);
      };
      get_ = [member](const S &s) { return profile::MemberValue(detail::to_scalar(s.*member)); };
      set_ = [member](S &s, const profile::MemberValue &v) {
        s.*member = std::get<M>(std::get<profile::Scalar>(v));
      };
    } else {
      using E = typename M::value_type;
      static_assert(std::is_same_v<M, std::vector<E>> && detail::kIsScalar<E>,
                    "a struct field is a property type or a std::vector of one");
      mismatch_ = [](const profile::StructMember &m) {
        return detail::member_mismatch(m, detail::scalar_index<E>(), true);
      };
      get_ = [member](const S &s) { return profile::MemberValue(detail::to_scalars(s.*member)); };
      set_ = [member](S &s, const profile::MemberValue &v) {
        s.*member = detail::from_scalars<E>(std::get<std::vector<profile::Scalar>>(v));
      };
    }
  }

  const std::string &id() const { return id_; }
  std::optional<std::string> mismatch(const profile::StructMember &member) const {
    return mismatch_(member);
  }
  profile::MemberValue get(const S &s) const { return get_(s); }
  void set(S &s, const profile::MemberValue &value) const { set_(s, value); }

private:
  std::string id_;
  std::function<std::optional<std::string>(const profile::StructMember &)> mismatch_;
  std::function<profile::MemberValue(const S &)> get_;
  std::function<void(S &, const profile::MemberValue &)> set_;
};

namespace detail {

std::optional<std::string> struct_mismatch(
    const profile::StructProperty &definition, const std::vector<std::string> &field_ids,
    const std::function<std::optional<std::string>(std::size_t, const profile::StructMember &)>
        &check);

template <typename T>
class ScalarBinding final : public PropertyBinding {
public:
  ScalarBinding(T &variable, ChangeCallback<T> callback)
      : variable_(variable), callback_(std::move(callback)) {}
  std::optional<std::string> mismatch(const profile::PropertyDefinition &d) const override {
    return simple_mismatch(d, scalar_index<T>(), false);
  }
  profile::PropertyValue get() const override { return to_scalar(variable_); }
  std::function<void()> set(const profile::PropertyValue &value) override {
    T old_value = variable_;
    variable_ = std::get<T>(std::get<profile::Scalar>(value));
    return notification(callback_, std::move(old_value), variable_);
  }

private:
  T &variable_;
  ChangeCallback<T> callback_;
};

template <typename T>
class AtomicBinding final : public PropertyBinding {
public:
  AtomicBinding(std::atomic<T> &variable, ChangeCallback<T> callback)
      : variable_(variable), callback_(std::move(callback)) {}
  std::optional<std::string> mismatch(const profile::PropertyDefinition &d) const override {
    return simple_mismatch(d, scalar_index<T>(), false);
  }
  profile::PropertyValue get() const override { return to_scalar(variable_.load()); }
  std::function<void()> set(const profile::PropertyValue &value) override {
    const T new_value = std::get<T>(std::get<profile::Scalar>(value));
    return notification(callback_, variable_.exchange(new_value), new_value);
  }

private:
  std::atomic<T> &variable_;
  ChangeCallback<T> callback_;
};

template <typename T>
class SequenceBinding final : public PropertyBinding {
public:
  SequenceBinding(std::vector<T> &variable, ChangeCallback<std::vector<T>> callback)
      : variable_(variable), callback_(std::move(callback)) {}
  std::optional<std::string> mismatch(const profile::PropertyDefinition &d) const override {
    return simple_mismatch(d, scalar_index<T>(), true);
  }
  profile::PropertyValue get() const override { return to_scalars(variable_); }
  std::function<void()> set(const profile::PropertyValue &value) override {
    std::vector<T> old_value = variable_;
    variable_ = from_scalars<T>(std::get<std::vector<profile::Scalar>>(value));
    return notification(callback_, std::move(old_value), variable_);
  }

private:
  std::vector<T> &variable_;
  ChangeCallback<std::vector<T>> callback_;
};

template <typename S>
std::optional<std::string> fields_mismatch(const profile::StructProperty &d,
                                           const std::vector<Field<S>> &fields) {
  std::vector<std::string> ids;
  for (const auto &f : fields)
    ids.push_back(f.id());
  return struct_mismatch(d, ids, [&](std::size_t i, const profile::StructMember &member) {
    return fields[i].mismatch(member);
  });
}

template <typename S>
profile::StructValue struct_value(const S &s, const std::vector<Field<S>> &fields) {
  profile::StructValue value;
  for (const auto &f : fields)
    value.members.emplace_back(f.id(), f.get(s));
  return value;
}

// Sets the members `value` names; the others keep theirs.
template <typename S>
void assign_members(S &s, const profile::StructValue &value, const std::vector<Field<S>> &fields) {
  for (const auto &[id, member] : value.members)
    for (const auto &f : fields)
      if (f.id() == id)
        f.set(s, member);
}

template <typename S>
class StructBinding final : public PropertyBinding {
public:
  StructBinding(S &variable, std::vector<Field<S>> fields, ChangeCallback<S> callback)
      : variable_(variable), fields_(std::move(fields)), callback_(std::move(callback)) {}
  std::optional<std::string> mismatch(const profile::PropertyDefinition &d) const override {
    const auto *s = std::get_if<profile::StructProperty>(&d);
    if (s == nullptr)
      return "the variable is a struct, the PRF property is not";
    return fields_mismatch(*s, fields_);
  }
  profile::PropertyValue get() const override { return struct_value(variable_, fields_); }
  std::function<void()> set(const profile::PropertyValue &value) override {
    S old_value = variable_;
    assign_members(variable_, std::get<profile::StructValue>(value), fields_);
    return notification(callback_, std::move(old_value), variable_);
  }

private:
  S &variable_;
  std::vector<Field<S>> fields_;
  ChangeCallback<S> callback_;
};

template <typename S>
class StructSequenceBinding final : public PropertyBinding {
public:
  StructSequenceBinding(std::vector<S> &variable, std::vector<Field<S>> fields,
                        ChangeCallback<std::vector<S>> callback)
      : variable_(variable), fields_(std::move(fields)), callback_(std::move(callback)) {}
  std::optional<std::string> mismatch(const profile::PropertyDefinition &d) const override {
    const auto *s = std::get_if<profile::StructSequenceProperty>(&d);
    if (s == nullptr)
      return "the variable is a struct sequence, the PRF property is not";
    return fields_mismatch(s->element, fields_);
  }
  profile::PropertyValue get() const override {
    std::vector<profile::StructValue> values;
    for (const auto &s : variable_)
      values.push_back(struct_value(s, fields_));
    return values;
  }
  // Each element starts from S{}: members an element does not name keep S's defaults.
  std::function<void()> set(const profile::PropertyValue &value) override {
    std::vector<S> new_value;
    for (const auto &element : std::get<std::vector<profile::StructValue>>(value)) {
      S s{};
      assign_members(s, element, fields_);
      new_value.push_back(std::move(s));
    }
    std::vector<S> old_value = std::exchange(variable_, std::move(new_value));
    return notification(callback_, std::move(old_value), variable_);
  }

private:
  std::vector<S> &variable_;
  std::vector<Field<S>> fields_;
  ChangeCallback<std::vector<S>> callback_;
};

} // namespace detail

// The properties of one component. Not synchronized: the component's property lock guards it.
class PropertySet {
public:
  using Json = nlohmann::json;

  // From the component's constructor. Binding an id twice replaces the first binding.
  void bind(std::string id, std::unique_ptr<PropertyBinding> binding);

  // Takes the PRF definitions, checks every binding against them (the error lists every
  // mismatch) and gives each property its PRF default, if it has one.
  Expected<void> load(std::vector<profile::PropertyDefinition> definitions);

  // An execparam from the command line: `text` as the profile would write it.
  tl::expected<void, std::string> apply_text(const std::string &id, const std::string &text);

  // {id: value}: every id must exist, be configurable (kind configure or property, not
  // read-only) and every value fit its definition, or nothing is applied (bad request naming
  // each bad property). Returns the change notifications to run.
  control::CallResult<std::vector<std::function<void()>>> configure(const Json &properties);

  // The ids' values ({id: value}, null when a property has none); every queryable property
  // when `ids` is empty.
  control::CallResult<Json> query(const std::vector<std::string> &ids) const;

  const profile::PropertyDefinition *find(std::string_view id) const;
  // The ids bound by the component's code, defined in its PRF or not.
  std::vector<std::string> bound_ids() const;

private:
  Json value_json(const profile::PropertyDefinition &definition) const;
  std::function<void()> apply(const std::string &id, const profile::PropertyValue &value);

  std::vector<profile::PropertyDefinition> definitions_;
  std::map<std::string, std::unique_ptr<PropertyBinding>, std::less<>> bindings_;
  std::map<std::string, profile::PropertyValue, std::less<>> values_; // unbound properties
};

} // namespace rsca::component
