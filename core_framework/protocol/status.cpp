#include "protocol/status.hpp"

namespace rsca::protocol {

std::string_view to_string(Status status) {
  switch (status) {
  case Status::Ok:
    return "ok";
  case Status::BadRequest:
    return "bad request";
  case Status::NotFound:
    return "not found";
  case Status::Failed:
    return "failed";
  case Status::Timeout:
    return "timeout";
  case Status::Unavailable:
    return "unavailable";
  case Status::Rejected:
    return "rejected";
  }
  return "unknown";
}

bool is_known(std::int32_t status) {
  return status >= static_cast<std::int32_t>(Status::Ok) &&
         status <= static_cast<std::int32_t>(Status::Rejected);
}

} // namespace rsca::protocol
