#include "process/run_program.hpp"

#include <signal.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <string_view>

#include <fmt/format.h>

namespace rsca::process {

namespace fs = std::filesystem;

std::optional<fs::path> find_program(const std::string &name) {
  const char *path = std::getenv("PATH");
  std::string_view dirs = path != nullptr ? path : "/usr/bin:/bin";
  while (true) {
    const auto colon = dirs.find(':');
    const fs::path candidate = fs::path(dirs.substr(0, colon)) / name;
    std::error_code ec;
    if (fs::is_regular_file(candidate, ec) && ::access(candidate.c_str(), X_OK) == 0)
      return candidate;
    if (colon == std::string_view::npos)
      return std::nullopt;
    dirs.remove_prefix(colon + 1);
  }
}

tl::expected<void, std::string> run_to_end(const Command &command,
                                           std::chrono::milliseconds timeout) {
  const std::string name = command.program.filename().string();
  auto child = spawn(command, Group::Caller);
  if (!child)
    return tl::unexpected(child.error().to_string());
  int status = 0;
  if (!wait_exited(child->pidfd, timeout)) {
    ::kill(child->pid, SIGKILL);
    while (::waitpid(child->pid, &status, 0) < 0 && errno == EINTR) {
    }
    return tl::unexpected(
        fmt::format("{} did not finish within {} ms and was killed", name, timeout.count()));
  }
  while (::waitpid(child->pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0)
    return {};
  return tl::unexpected(
      WIFEXITED(status) ? fmt::format("{} failed with exit status {}", name, WEXITSTATUS(status))
                        : fmt::format("{} ended by signal {}", name, WTERMSIG(status)));
}

} // namespace rsca::process
