// The node's side of a fork server: one component executable started once, loaded, and asked to
// fork a process for each component of that executable (process/fork_service.hpp says why, and
// what the server does). A process started this way is what process::spawn would have started
// (the same checks before, the same descriptors, group, environment and CPUs after), but is the
// caller's child only because the caller is a child subreaper (PR_SET_CHILD_SUBREAPER): a fork
// server is for a caller that is one, as the GPP's process launcher is.
//
// A ForkServer owns its server process: destroying it closes the socket (the server exits) and
// kills and reaps the server. One thread at a time may use it.
#pragma once

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/diagnostic.hpp"
#include "process/credentials.hpp"
#include "process/fd.hpp"
#include "process/spawn.hpp"

namespace rsca::process {

// Whether `program` is an executable built with rsca's component runtime, which serves forks
// when asked: its bytes hold the fork server's ready message. Read once per program by whoever
// keeps fork servers.
bool may_serve_forks(const std::filesystem::path &program);

class ForkServer {
public:
  // Starts `program` as a fork server with `env` added to this process's environment (what its
  // dynamic loader must see, as LD_LIBRARY_PATH), in a process group of its own, as `user` (what
  // it forks runs as that user too; none: this process's), and waits at most `timeout` for it to
  // serve. An error when it cannot start or does not serve in time: nothing is left running.
  static Expected<ForkServer> start(const std::filesystem::path &program,
                                    const std::vector<std::pair<std::string, std::string>> &env,
                                    std::chrono::milliseconds timeout,
                                    const std::optional<Credentials> &user = std::nullopt);

  ForkServer(ForkServer &&) noexcept = default;
  ForkServer &operator=(ForkServer &&) noexcept;
  ForkServer(const ForkServer &) = delete;
  ForkServer &operator=(const ForkServer &) = delete;
  ~ForkServer();

  // Starts the command's process (command.program, its argv[0], names the server's executable
  // file, by the path it was started with or another link to the same file; its log file and
  // inherited descriptors as process::spawn gives them) in a process group of its own, on the
  // calling thread's CPUs, as a spawned process would inherit them. An error names the step; one
  // that leaves the server unusable (it died, or did not answer within `timeout`) makes alive()
  // false.
  Expected<Child> spawn(const Command &command, std::chrono::milliseconds timeout);

  bool alive() const { return static_cast<bool>(socket_); }
  pid_t pid() const { return server_.pid; }

private:
  ForkServer(Child server, Fd socket) : server_(std::move(server)), socket_(std::move(socket)) {}
  void stop();

  Child server_;
  Fd socket_;
};

} // namespace rsca::process
