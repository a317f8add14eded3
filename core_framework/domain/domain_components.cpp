// What nodes and components report to the DomainManager: processes that exited, connection
// problems (configure and query are domain_properties.cpp's).
#include <algorithm>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/names.hpp"
#include "control/operation.hpp"
#include "domain/domain_manager_impl.hpp"
#include "protocol/component_ops.hpp"

namespace rsca::domain {
namespace {

// `why` a process exited and the last lines of its log, each indented under it.
std::string with_log_tail(const std::string &why, const std::string &tail) {
  std::string out = fmt::format("{}; the last lines of its log (`rsca logs --failed` after a "
                                "failed launch shows it whole):",
                                why);
  std::size_t at = 0;
  while (at < tail.size()) {
    auto nl = tail.find('\n', at);
    if (nl == std::string::npos)
      nl = tail.size();
    out += fmt::format("\n    {}", std::string_view(tail).substr(at, nl - at));
    at = nl + 1;
  }
  return out;
}

} // namespace

CallResult<protocol::Empty>
DomainManager::Impl::component_exited(const protocol::domain::ComponentExitedReport &r) {
  // Every component the process served: one, or those of a component host.
  const std::string why = r.status.empty() ? std::string("exited") : r.status;
  // A launch waiting for it fails with its last words: mostly why it exited.
  const std::string told = r.log_tail.empty() ? why : with_log_tail(why, r.log_tail);
  for (const auto &address : r.addresses) {
    components.exited(address, told); // a launch waiting for it fails at once
    endpoint->abandon(address, why);
  }
  mark_exited(
      [&r](const ComponentInstance &c) {
        return std::find(r.addresses.begin(), r.addresses.end(), c.address) != r.addresses.end();
      },
      why);
  return protocol::Empty{};
}

void DomainManager::Impl::mark_exited(const std::function<bool(const ComponentInstance &)> &which,
                                      const std::string &why) {
  applications.update_all([&](Application &app) {
    for (auto &c : app.components) {
      if (c.pid == 0 || c.state == ComponentState::Exited || !which(c))
        continue;
      components.exited(c.address, why);
      c.state = ComponentState::Exited;
      spdlog::warn("component {} of application {} exited unexpectedly: {}; the application is "
                   "degraded",
                   c.id, app.name, why);
      events->publish(
          "component.exited",
          {{"application", app.name}, {"component", c.id}, {"node", c.node}, {"why", why}});
    }
  });
}

// A component saw its writer miss a connection's deadline or lose liveliness.
CallResult<protocol::Empty>
DomainManager::Impl::connection_problem(const protocol::domain::ConnectionProblemReport &r) {
  spdlog::warn("connection {} of application {} ({}): {} ({} times)", excerpt(r.connection),
               excerpt(r.application), excerpt(r.component), excerpt(r.problem), r.count);
  events->publish("connection.problem", protocol::encode(r));
  return protocol::Empty{};
}

} // namespace rsca::domain
