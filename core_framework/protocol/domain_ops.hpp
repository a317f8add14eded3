// The domain.* reports: what nodes and components tell the domain daemon without waiting for
// its reply.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "protocol/codec.hpp"

namespace rsca::protocol::domain {

// A process a node started exited without being asked to.
struct ComponentExitedReport {
  std::string application;
  std::string component;
  std::vector<std::string> addresses; // every component it served: one, or a host's
  std::int64_t pid = 0;
  std::string device;
  std::string status; // "exited with 3", "killed by SIGSEGV"
  std::int32_t exit_code = 0;
  std::int32_t signal = 0;
  static constexpr auto fields() {
    using R = ComponentExitedReport;
    return std::tuple{
        required("application", &R::application), required("component", &R::component),
        required("addresses", &R::addresses),     required("pid", &R::pid),
        required("device", &R::device),           required("status", &R::status),
        optional("exit_code", &R::exit_code),     optional("signal", &R::signal)};
  }
};

// QoS problems of a provides port's connection since the last report.
struct ConnectionProblemReport {
  std::string application;
  std::string component;
  std::string connection;
  std::string problem; // "deadline missed", "liveliness lost"
  std::int64_t count = 0;
  static constexpr auto fields() {
    using R = ConnectionProblemReport;
    return std::tuple{required("application", &R::application),
                      required("component", &R::component), required("connection", &R::connection),
                      required("problem", &R::problem), required("count", &R::count)};
  }
};

struct ComponentExited {
  static constexpr std::string_view name = "domain.component_exited";
  using Request = ComponentExitedReport;
  using Reply = Empty;
};
struct ConnectionProblem {
  static constexpr std::string_view name = "domain.connection_problem";
  using Request = ConnectionProblemReport;
  using Reply = Empty;
};

} // namespace rsca::protocol::domain
