// The GPP's pool of fork servers (gpp/fork_servers.hpp) on real processes: one server per
// executable file (a second link to it shares it, a copy does not), an executable that does not
// serve forks is left to be executed, a server that died is replaced, the least recently used
// goes past kMaxServers, and one whose file was deleted goes when a new one starts. The program is
// rsca-test-forked (tests/unit/forked_program); servers are counted in /proc among this process's
// children.
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <string>

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>

#include "eventually.hpp"
#include "gpp/fork_servers.hpp"
#include "temp_dir.hpp"

namespace fs = std::filesystem;
using rsca::gpp::ExecRequest;
using rsca::gpp::ForkServers;

namespace {

const fs::path kForkedProgram = RSCA_TEST_FORKED;

// This process's children that are fork servers, by pid.
std::set<pid_t> fork_servers_here() {
  std::set<pid_t> servers;
  for (const auto &entry : fs::directory_iterator("/proc")) {
    const auto name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos)
      continue;
    std::ifstream stat(entry.path() / "stat");
    std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
    const auto paren = text.rfind(')');
    if (paren == std::string::npos || text.size() < paren + 4 || text[paren + 2] == 'Z')
      continue;
    const long parent = std::atol(text.c_str() + paren + 4);
    std::ifstream cmdline(entry.path() / "cmdline");
    std::string command((std::istreambuf_iterator<char>(cmdline)),
                        std::istreambuf_iterator<char>());
    if (parent == ::getpid() && command.find("--rsca-fork-server") != std::string::npos)
      servers.insert(static_cast<pid_t>(std::stol(name)));
  }
  return servers;
}

// The files this process's fork servers run (" (deleted)" as the kernel says it).
std::set<std::string> served_files() {
  std::set<std::string> files;
  for (const pid_t server : fork_servers_here())
    files.insert(fs::read_symlink(fs::path("/proc") / std::to_string(server) / "exe").string());
  return files;
}

// The real uid of process `pid`.
long uid_of(pid_t pid) {
  std::ifstream status(fs::path("/proc") / std::to_string(pid) / "status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("Uid:", 0) == 0)
      return std::stol(line.substr(4));
  return -1;
}

// Forks `program` through the pool, which must fork it, as `user` (none: as this process), and
// reaps what it started.
void fork_through(ForkServers &pool, const fs::path &program,
                  const std::optional<rsca::process::Credentials> &user = std::nullopt) {
  ExecRequest request;
  request.program = program;
  request.args = {"0"};
  request.user = user;
  auto child = pool.fork(request);
  INFO(program.string());
  REQUIRE(child.has_value());
  int status = 0;
  REQUIRE(::waitpid(child->pid, &status, 0) == child->pid);
  CHECK(WIFEXITED(status));
}

} // namespace

TEST_CASE("the GPP's fork servers: one per file, none for a program that does not serve, a dead "
          "one replaced",
          "[process][fork_server]") {
  REQUIRE(::prctl(PR_SET_CHILD_SUBREAPER, 1) == 0);
  rsca::test::TempDir dir;
  const fs::path linked = dir.path() / "linked";
  const fs::path copied = dir.path() / "copied";
  fs::create_hard_link(kForkedProgram, linked);
  fs::copy_file(kForkedProgram, copied);
  fs::permissions(copied, fs::perms::owner_all);
  {
    ForkServers pool;
    fork_through(pool, kForkedProgram);
    fork_through(pool, kForkedProgram);
    fork_through(pool, linked); // the same file: the same server
    const auto first = fork_servers_here();
    CHECK(first.size() == 1);
    fork_through(pool, copied); // another file: a server of its own
    CHECK(fork_servers_here().size() == 2);

    ExecRequest not_serving;
    not_serving.program = "/bin/true";
    CHECK_FALSE(pool.fork(not_serving).has_value()); // left to be executed
    CHECK(fork_servers_here().size() == 2);

    // A server that died: that request is left to be executed, the next starts a new server.
    REQUIRE(::kill(*first.begin(), SIGKILL) == 0);
    REQUIRE(rsca::test::eventually([&] { return fork_servers_here().size() == 1; }));
    ExecRequest request;
    request.program = kForkedProgram;
    request.args = {"0"};
    CHECK_FALSE(pool.fork(request).has_value());
    fork_through(pool, kForkedProgram);
    const auto now = fork_servers_here();
    CHECK(now.size() == 2);
    CHECK(now.count(*first.begin()) == 0);
  }
  // The pool's servers go with it.
  CHECK(fork_servers_here().empty());
}

TEST_CASE("the GPP's fork servers: the least recently used goes past the limit, and one whose "
          "file was deleted goes when another starts",
          "[process][fork_server]") {
  REQUIRE(::prctl(PR_SET_CHILD_SUBREAPER, 1) == 0);
  rsca::test::TempDir dir;
  std::vector<fs::path> programs;
  for (std::size_t i = 0; i <= ForkServers::kMaxServers; ++i) {
    programs.push_back(dir.path() / ("program" + std::to_string(i)));
    fs::copy_file(kForkedProgram, programs.back());
    fs::permissions(programs.back(), fs::perms::owner_all);
  }
  ForkServers pool;
  for (std::size_t i = 0; i < ForkServers::kMaxServers; ++i)
    fork_through(pool, programs[i]);
  REQUIRE(fork_servers_here().size() == ForkServers::kMaxServers);
  fork_through(pool, programs[0]); // used again: the least recently used is now programs[1]'s
  fork_through(pool, programs[ForkServers::kMaxServers]);
  auto files = served_files();
  CHECK(files.size() == ForkServers::kMaxServers);
  CHECK(files.count(programs[0].string()) == 1);
  CHECK(files.count(programs[1].string()) == 0);
  CHECK(files.count(programs[ForkServers::kMaxServers].string()) == 1);

  // A deleted file's server goes when the next one starts, rather than the least recently used
  // (programs[2]'s).
  const fs::path deleted = programs[ForkServers::kMaxServers - 1];
  fs::remove(deleted);
  const fs::path fresh = dir.path() / "fresh";
  fs::copy_file(kForkedProgram, fresh);
  fs::permissions(fresh, fs::perms::owner_all);
  fork_through(pool, fresh);
  files = served_files();
  CHECK(files.size() == ForkServers::kMaxServers);
  CHECK(files.count(deleted.string() + " (deleted)") == 0);
  CHECK(files.count(programs[2].string()) == 1);
  CHECK(files.count(fresh.string()) == 1);
}

TEST_CASE("the GPP's fork servers: one per user, each running as its user",
          "[process][fork_server]") {
  INFO("only root may start a process as another user: the tests run as root");
  REQUIRE(::geteuid() == 0);
  REQUIRE(::prctl(PR_SET_CHILD_SUBREAPER, 1) == 0);
  auto nobody = rsca::process::credentials_of("nobody");
  REQUIRE(nobody.has_value());
  {
    ForkServers pool;
    fork_through(pool, kForkedProgram, *nobody);
    const auto as_nobody = fork_servers_here();
    REQUIRE(as_nobody.size() == 1);
    CHECK(uid_of(*as_nobody.begin()) == static_cast<long>(nobody->uid));
    fork_through(pool, kForkedProgram); // the same file, as this process: a server of its own
    const auto both = fork_servers_here();
    CHECK(both.size() == 2);
    for (const pid_t server : both)
      if (as_nobody.count(server) == 0)
        CHECK(uid_of(server) == static_cast<long>(::geteuid()));
    fork_through(pool, kForkedProgram, *nobody);
    CHECK(fork_servers_here() == both);
  }
  CHECK(fork_servers_here().empty());
}
