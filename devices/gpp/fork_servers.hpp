// The GPP's fork servers (process/fork_server.hpp): the first process of an executable built with
// rsca's runtime starts a fork server of it, and that process and the next are forked from it
// instead of executed. One server per executable file (not path: two packages with the same
// verified file share one; a file rewritten is a new file), library path and user; at most
// kMaxServers, the least recently used stopped for a new one, and those whose file was deleted
// stopped when a new one starts. An executable that does not serve forks, or a server that fails,
// falls back to process::spawn, said in the node's log.
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>

#include "common/diagnostic.hpp"
#include "process/fork_server.hpp"
#include "process_launcher.hpp"

namespace rsca::gpp {

class ForkServers {
public:
  static constexpr std::size_t kMaxServers = 16;

  // The request's process forked by its executable's fork server; nullopt when no server can
  // fork it (an executable that does not serve, a server that failed, a request it refused): the
  // caller executes it, which reports what is wrong with the request itself.
  std::optional<process::Child> fork(const ExecRequest &request);

private:
  struct Entry {
    process::ForkServer server;
    std::uint64_t last_used = 0;
  };
  process::ForkServer *server_for(const ExecRequest &request, const std::string &key);
  // Stops the servers whose executable no path names any more (it would stay on disk for them).
  void drop_deleted();
  void make_room();

  std::mutex mutex_;
  std::map<std::string, Entry> servers_; // by key (fork_servers.cpp)
  std::map<std::string, bool> serves_;   // by key: whether its executable serves forks
  std::uint64_t uses_ = 0;
};

} // namespace rsca::gpp
