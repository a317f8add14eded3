// gpp/run_as.hpp: the run_as property to credentials, and what the node says of it.
#include "gpp/run_as.hpp"

#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

namespace rsca::gpp {
namespace {

tl::unexpected<Error> run_as_error(const node::DeviceContext &context, std::string message) {
  return make_error({context.id, 0, 0}, "run_as", std::move(message));
}

} // namespace

Expected<std::optional<process::Credentials>> component_user(const node::DeviceContext &context) {
  std::optional<std::string> dcd_value;
  if (context.overrides.contains("run_as")) {
    const auto &value = context.overrides.at("run_as");
    if (!value.is_string())
      return run_as_error(context, fmt::format("{}: run_as is not a user name", context.id));
    dcd_value = value.get<std::string>();
  }
  const std::string wanted = dcd_value.value_or(kDefaultRunAs);
  if (!process::may_change_user()) {
    spdlog::info("{}: this node runs as uid {}, not root, and cannot change user: its component "
                 "processes run as it does (run_as {} not taken)",
                 context.id, ::geteuid(), wanted);
    return std::nullopt;
  }
  auto user = process::credentials_of(wanted);
  if (!user && dcd_value)
    return run_as_error(context, fmt::format("{}: run_as: {}", context.id,
                                             user.error().diagnostics().front().message));
  if (!user) {
    user = process::credentials_of(kFallbackRunAs);
    if (!user)
      return run_as_error(context, fmt::format("{}: no user {} nor {} on this host to run "
                                               "component processes as; set the GPP's run_as in "
                                               "the node's DCD",
                                               context.id, kDefaultRunAs, kFallbackRunAs));
    spdlog::warn("{}: there is no user {} on this host (the rsca Debian package creates it): "
                 "component processes run as {}; set the GPP's run_as in the node's DCD to "
                 "choose another user",
                 context.id, kDefaultRunAs, kFallbackRunAs);
  }
  if (user->uid == 0) {
    spdlog::warn("{}: component processes run as root: the DCD sets run_as {}", context.id, wanted);
    return std::nullopt;
  }
  spdlog::info("{}: component processes run as {} (uid {}, gid {})", context.id, user->user,
               user->uid, user->gid);
  return std::move(*user);
}

} // namespace rsca::gpp
