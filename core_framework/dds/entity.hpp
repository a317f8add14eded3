// Ownership of Cyclone DDS C handles: an Entity deletes its handle (and so its children) when it
// goes; a Qos frees itself. Failures of the C API become errors that name the call.
#pragma once

#include <memory>
#include <string_view>
#include <utility>

#include <dds/dds.h>

#include "common/diagnostic.hpp"

namespace rsca::dds {

class Entity {
public:
  Entity() = default;
  explicit Entity(dds_entity_t handle) : handle_(handle) {}
  ~Entity() { reset(); }
  Entity(Entity &&other) noexcept : handle_(std::exchange(other.handle_, 0)) {}
  Entity &operator=(Entity &&other) noexcept {
    if (this != &other) {
      reset();
      handle_ = std::exchange(other.handle_, 0);
    }
    return *this;
  }
  Entity(const Entity &) = delete;
  Entity &operator=(const Entity &) = delete;

  dds_entity_t get() const { return handle_; }
  explicit operator bool() const { return handle_ > 0; }
  void reset() {
    if (handle_ > 0)
      dds_delete(handle_);
    handle_ = 0;
  }

private:
  dds_entity_t handle_ = 0;
};

struct QosDeleter {
  void operator()(dds_qos_t *qos) const { dds_delete_qos(qos); }
};
using Qos = std::unique_ptr<dds_qos_t, QosDeleter>;
inline Qos make_qos() {
  return Qos(dds_create_qos());
}

// The entity a C call returned, or an error naming `what` and Cyclone's reason.
Expected<Entity> checked(dds_entity_t result, std::string_view what);
// An error for a negative return code of a C call.
Error dds_error(dds_return_t result, std::string_view what);

} // namespace rsca::dds
