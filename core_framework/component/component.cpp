#include "component/component.hpp"

#include <spdlog/spdlog.h>

namespace rsca::component {

std::string_view to_string(State state) {
  switch (state) {
  case State::Loaded:
    return "loaded";
  case State::Initialized:
    return "initialized";
  case State::Started:
    return "started";
  case State::Stopped:
    return "stopped";
  case State::Released:
    return "released";
  }
  return "unknown";
}

Component::Component(Context context) : context_(std::move(context)) {
  if (!context_.logger)
    context_.logger = spdlog::default_logger();
}

Component::~Component() = default;

} // namespace rsca::component
