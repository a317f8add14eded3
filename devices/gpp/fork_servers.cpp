// gpp/fork_servers.hpp: which server serves a request, starting one, and letting one go.
#include "gpp/fork_servers.hpp"

#include <algorithm>
#include <chrono>
#include <utility>
#include <vector>

#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

namespace rsca::gpp {
namespace {

using namespace std::chrono_literals;

// How long a server has to serve once started, and to answer a request: far above what either
// takes (a few milliseconds), for a loaded host and a sanitized build.
constexpr auto kStartTimeout = 10s;
constexpr auto kRequestTimeout = 10s;
// How many executables the node remembers serve forks or not.
constexpr std::size_t kMaxRemembered = 1024;

// Read once, as a process starts (by the dynamic loader, glibc, the sanitizers), so a fork cannot
// change them: the server must be started with them.
bool read_at_start(const std::string &name) {
  for (const char *prefix : {"LD_", "GLIBC_TUNABLES", "MALLOC_", "ASAN_", "UBSAN_", "LSAN_",
                             "TSAN_", "LLVM_PROFILE_FILE"})
    if (name.rfind(prefix, 0) == 0)
      return true;
  return false;
}

// What the server must be started with: the request's variables read at start.
std::vector<std::pair<std::string, std::string>> startup_environment(const ExecRequest &request) {
  std::vector<std::pair<std::string, std::string>> env;
  for (const auto &variable : request.env)
    if (read_at_start(variable.first))
      env.push_back(variable);
  return env;
}

// The executable's file, and what its loader sees; empty when it cannot be read (spawn then says
// why). The file, not its path: the node's package cache links the same verified, read-only
// content into every package that has it, so the packages of two applications share a server. A
// file is rewritten as a new file (a new inode); and the inode of one a server runs cannot be
// reused while it runs.
std::string key_of(const ExecRequest &request) {
  struct stat status {};
  if (::stat(request.program.c_str(), &status) != 0 || !S_ISREG(status.st_mode))
    return {};
  std::string key = fmt::format("{}:{}:{}", status.st_dev, status.st_ino, status.st_size);
  for (const auto &[name, value] : startup_environment(request))
    key += fmt::format("\n{}={}", name, value);
  // What it forks runs as its server's user: one server per user.
  key += fmt::format("\nuser {}", request.user ? request.user->uid : ::geteuid());
  return key;
}

} // namespace

std::optional<process::Child> ForkServers::fork(const ExecRequest &request) {
  const std::lock_guard lock(mutex_);
  const std::string key = key_of(request);
  if (key.empty())
    return std::nullopt;
  auto *server = server_for(request, key);
  if (server == nullptr)
    return std::nullopt;
  auto child = server->spawn(request, kRequestTimeout);
  if (child)
    return std::move(*child);
  // Executed instead, which says again what is wrong with the request itself.
  spdlog::warn("fork server of {} (pid {}): {}; the process is executed", request.program.string(),
               server->pid(), child.error().to_string());
  if (!server->alive())
    servers_.erase(key);
  return std::nullopt;
}

process::ForkServer *ForkServers::server_for(const ExecRequest &request, const std::string &key) {
  if (auto found = servers_.find(key); found != servers_.end()) {
    found->second.last_used = ++uses_;
    return &found->second.server;
  }
  if (serves_.size() >= kMaxRemembered)
    serves_.clear(); // each is read again when next used
  auto [serves, first] = serves_.try_emplace(key, false);
  if (first)
    serves->second = process::may_serve_forks(request.program);
  if (!serves->second)
    return nullptr;
  auto started = process::ForkServer::start(request.program, startup_environment(request),
                                            kStartTimeout, request.user);
  if (!started) {
    spdlog::warn("{}; its processes are executed", started.error().to_string());
    serves->second = false;
    return nullptr;
  }
  // Started from a thread that may be on a placement's CPUs: the server itself runs on the node's.
  cpu_set_t node_cpus;
  if (::sched_getaffinity(::getpid(), sizeof node_cpus, &node_cpus) == 0)
    ::sched_setaffinity(started->pid(), sizeof node_cpus, &node_cpus);
  drop_deleted();
  make_room();
  spdlog::info("fork server of {} started (pid {}{})", request.program.string(), started->pid(),
               request.user ? ", as " + request.user->user : "");
  auto &entry = servers_.emplace(key, Entry{std::move(*started), ++uses_}).first->second;
  return &entry.server;
}

void ForkServers::drop_deleted() {
  std::erase_if(servers_, [](const auto &entry) {
    // The server's executable, even when no path names it any more: a package the cache let go.
    struct stat status {};
    const auto exe = fmt::format("/proc/{}/exe", entry.second.server.pid());
    const bool deleted = ::stat(exe.c_str(), &status) != 0 || status.st_nlink == 0;
    if (deleted)
      spdlog::info("fork server (pid {}) stopped: its executable is gone",
                   entry.second.server.pid());
    return deleted;
  });
}

void ForkServers::make_room() {
  if (servers_.size() < kMaxServers)
    return;
  const auto oldest = std::min_element(servers_.begin(), servers_.end(), [](auto &a, auto &b) {
    return a.second.last_used < b.second.last_used;
  });
  spdlog::info("fork server (pid {}) stopped: the least recently used of {}",
               oldest->second.server.pid(), kMaxServers);
  servers_.erase(oldest);
}

} // namespace rsca::gpp
