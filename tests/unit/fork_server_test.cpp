// Fork servers (process/fork_server.hpp, process/fork_service.hpp) on real processes: a process
// forked from one has what process::spawn would have given it and is this process's child; a
// program that does not serve forks is refused and leaves nothing running; a server that died
// says so; a request that is not one is refused. The program forked is rsca-test-forked
// (tests/unit/forked_program), which says what it was given.
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>

#include "eventually.hpp"
#include "process/fork_request.hpp"
#include "process/fork_server.hpp"
#include "temp_dir.hpp"
#include "test_files.hpp"

using namespace std::chrono_literals;
using rsca::process::Command;
using rsca::process::ForkServer;
using rsca::test::slurp;
using rsca::test::TempDir;

namespace {

const std::filesystem::path kForked = RSCA_TEST_FORKED;

// The exit code of a child of this process, reaped.
int exit_code_of(pid_t pid) {
  int status = 0;
  REQUIRE(::waitpid(pid, &status, 0) == pid);
  REQUIRE(WIFEXITED(status));
  return WEXITSTATUS(status);
}

std::string command_line_of(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/cmdline", std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (auto &c : text)
    c = c == '\0' ? ' ' : c;
  return text;
}

ForkServer started_server() {
  // A process forked by a server is re-parented to its nearest subreaper: this process.
  REQUIRE(::prctl(PR_SET_CHILD_SUBREAPER, 1) == 0);
  auto server = ForkServer::start(kForked, {}, 10s);
  INFO((server ? "" : server.error().to_string()));
  REQUIRE(server.has_value());
  return std::move(*server);
}

} // namespace

TEST_CASE("a process forked from a fork server has what spawn would have given it",
          "[process][fork_server]") {
  TempDir dir;
  auto server = started_server();
  int pipe_ends[2];
  REQUIRE(::pipe2(pipe_ends, O_CLOEXEC) == 0);
  rsca::process::Fd read_end{pipe_ends[0]};
  rsca::process::Fd write_end{pipe_ends[1]};
  const Command command{.program = kForked,
                        .args = {"7", "second argument"},
                        .env = {{"RSCA_TEST_VALUE", "forty two"}},
                        .working_dir = dir.path(),
                        .log_file = dir.path() / "logs/forked.log",
                        .inherit = {{write_end.get(), 3}}};
  // On the calling thread's CPUs, as a spawned child: here CPU 0 alone.
  cpu_set_t saved;
  REQUIRE(::sched_getaffinity(0, sizeof saved, &saved) == 0);
  cpu_set_t zero;
  CPU_ZERO(&zero);
  CPU_SET(0, &zero);
  REQUIRE(::sched_setaffinity(0, sizeof zero, &zero) == 0);
  auto child = server.spawn(command, 10s);
  REQUIRE(::sched_setaffinity(0, sizeof saved, &saved) == 0);
  INFO((child ? "" : child.error().to_string()));
  REQUIRE(child.has_value());
  CHECK(exit_code_of(child->pid) == 7); // this process's child: it reaps it
  write_end.reset();
  char through[64] = {};
  CHECK(::read(read_end.get(), through, sizeof through - 1) > 0);
  CHECK(std::string(through) == "through 3\n");
  const std::string log = slurp(dir.path() / "logs/forked.log");
  INFO(log);
  CHECK_THAT(log, Catch::Contains("args: 7 second argument\n"));
  CHECK_THAT(log, Catch::Contains("cwd: " + dir.path().string() + "\n"));
  CHECK_THAT(log, Catch::Contains("value: forty two\n"));
  CHECK_THAT(log, Catch::Contains("server variable: unset\n"));
  CHECK_THAT(log, Catch::Contains("group: own\n"));
  CHECK_THAT(log, Catch::Contains("parent: " + std::to_string(::getpid()) + "\n"));
  CHECK_THAT(log, Catch::Contains("cpus: 1\n"));
  CHECK_THAT(log, Catch::Contains("stdin: empty\n"));
  CHECK_THAT(log, Catch::Contains("fd 4: closed\n"));         // the server's socket did not leak
  CHECK_THAT(log, Catch::Contains("descriptors: 0 1 2 3\n")); // only those it was given
  CHECK(server.alive());
}

// As spawn gives a child (spawn_test): whatever the server has open, blocks or ignores, the
// started process gets none of it.
TEST_CASE("a process forked with no descriptor to inherit has none of the server's, every "
          "signal's default action and none blocked",
          "[process][fork_server]") {
  TempDir dir;
  auto server = started_server();
  auto child =
      server.spawn({.program = kForked, .args = {"0"}, .log_file = dir.path() / "log"}, 10s);
  REQUIRE(child.has_value());
  CHECK(exit_code_of(child->pid) == 0);
  const std::string log = slurp(dir.path() / "log");
  INFO(log);
  CHECK_THAT(log, Catch::Contains("fd 4: closed\n"));
  CHECK_THAT(log, Catch::Contains("fd 3: closed\n"));       // the server's socket
  CHECK_THAT(log, Catch::Contains("descriptors: 0 1 2\n")); // none of the server's, however high
  CHECK_THAT(log, Catch::Contains("ignored signals: none\n"));
  CHECK_THAT(log, Catch::Contains("blocked signals: none\n"));
}

TEST_CASE("a fork server works under a low limit of descriptors", "[process][fork_server]") {
  TempDir dir;
  rlimit saved{};
  REQUIRE(::getrlimit(RLIMIT_NOFILE, &saved) == 0);
  rlimit low = saved;
  low.rlim_cur = 128; // the server inherits it (process::spawn needs 64 and more)
  REQUIRE(::setrlimit(RLIMIT_NOFILE, &low) == 0);
  auto server = started_server();
  REQUIRE(::setrlimit(RLIMIT_NOFILE, &saved) == 0);
  int pipe_ends[2];
  REQUIRE(::pipe2(pipe_ends, O_CLOEXEC) == 0);
  rsca::process::Fd read_end{pipe_ends[0]};
  rsca::process::Fd write_end{pipe_ends[1]};
  auto child = server.spawn({.program = kForked,
                             .args = {"5"},
                             .log_file = dir.path() / "log",
                             .inherit = {{write_end.get(), 3}}},
                            10s);
  REQUIRE(child.has_value());
  CHECK(exit_code_of(child->pid) == 5);
  CHECK_THAT(slurp(dir.path() / "log"), Catch::Contains("args: 5\n"));
}

TEST_CASE("a fork server starts many processes, one after the other", "[process][fork_server]") {
  TempDir dir;
  auto server = started_server();
  for (int i = 0; i < 20; ++i) {
    auto child = server.spawn({.program = kForked, .args = {std::to_string(i)}}, 10s);
    REQUIRE(child.has_value());
    CHECK(exit_code_of(child->pid) == i);
  }
}

TEST_CASE("a process forked from a fork server has its own command line, can be signalled as a "
          "group and watched",
          "[process][fork_server]") {
  TempDir dir;
  auto server = started_server();
  auto child = server.spawn(
      {.program = kForked, .args = {"wait", "--flag"}, .log_file = dir.path() / "log"}, 10s);
  REQUIRE(child.has_value());
  REQUIRE(::kill(-child->pid, 0) == 0); // its group exists as soon as its pid is known
  // Once it runs main (it has said something), /proc shows its arguments (cut to the server's
  // room where the kernel refuses a new command line).
  REQUIRE(rsca::test::eventually(
      [&] { return slurp(dir.path() / "log").find("fd 4:") != std::string::npos; }));
  CHECK_THAT(command_line_of(child->pid), Catch::StartsWith(kForked.string() + " wait --flag"));
  REQUIRE(::kill(-child->pid, SIGKILL) == 0);
  CHECK(rsca::process::wait_exited(child->pidfd, 10s));
  int status = 0;
  REQUIRE(::waitpid(child->pid, &status, 0) == child->pid);
  CHECK(WIFSIGNALED(status));
}

TEST_CASE("a program that does not serve forks is not started as a fork server",
          "[process][fork_server]") {
  CHECK(rsca::process::may_serve_forks(kForked));
  CHECK_FALSE(rsca::process::may_serve_forks("/bin/true"));
  CHECK_FALSE(rsca::process::may_serve_forks("/no/such/program"));
  REQUIRE(::prctl(PR_SET_CHILD_SUBREAPER, 1) == 0);
  // Started anyway, it exits (or would stay silent): an error, and nothing left running.
  auto server = ForkServer::start("/bin/true", {}, 10s);
  REQUIRE_FALSE(server.has_value());
  CHECK_THAT(server.error().to_string(), Catch::Contains("does not serve forks"));
  CHECK(::waitpid(-1, nullptr, WNOHANG) < 0); // no child left, reaped or not
  CHECK(errno == ECHILD);
}

TEST_CASE("a fork server that died says so, and starts nothing", "[process][fork_server]") {
  auto server = started_server();
  REQUIRE(::kill(server.pid(), SIGKILL) == 0);
  auto child = server.spawn({.program = kForked, .args = {"0"}}, 10s);
  REQUIRE_FALSE(child.has_value());
  CHECK_THAT(child.error().to_string(), Catch::Contains("did not answer"));
  CHECK_FALSE(server.alive());
}

TEST_CASE("a fork server's checks are spawn's: a bad working directory starts nothing",
          "[process][fork_server]") {
  auto server = started_server();
  auto child = server.spawn({.program = kForked, .working_dir = "/no/such/dir"}, 10s);
  REQUIRE_FALSE(child.has_value());
  CHECK_THAT(child.error().to_string(), Catch::Contains("no such directory"));
  CHECK(server.alive());
}

TEST_CASE("a fork request is checked: keys, numbers, descriptors, size", "[process][fork_server]") {
  using rsca::process::decode_fork_request;
  using rsca::process::ForkRequest;
  const ForkRequest request{.program = "/bin/x",
                            .args = {"a", ""},
                            .env = {{"NAME", "a=b"}},
                            .working_dir = "/tmp",
                            .cpus = {0, 3},
                            .log = true,
                            .fd_numbers = {3, 4}};
  const auto decoded = decode_fork_request(encode(request), 3);
  REQUIRE(decoded.has_value());
  CHECK(decoded->program == "/bin/x");
  CHECK(decoded->args == request.args);
  CHECK(decoded->env == request.env);
  CHECK(decoded->working_dir == "/tmp");
  CHECK(decoded->cpus == request.cpus);
  CHECK(decoded->log);
  CHECK(decoded->fd_numbers == request.fd_numbers);

  CHECK_FALSE(decode_fork_request(encode(request), 2)); // a descriptor missing
  using namespace std::string_literals;
  CHECK_FALSE(decode_fork_request("what\0x\0"s, 0));         // an unknown key
  CHECK_FALSE(decode_fork_request("arg\0unterminated"s, 0)); // a pair cut short
  CHECK_FALSE(decode_fork_request("cpu\0-1\0"s, 0));         // not a CPU
  CHECK_FALSE(decode_fork_request("cpu\0 1\0"s, 0));         // not whole
  CHECK_FALSE(decode_fork_request("fd\0"
                                  "2\0"s,
                                  1));               // a standard stream
  CHECK_FALSE(decode_fork_request("env\0=x\0"s, 0)); // no name
  CHECK_FALSE(decode_fork_request(std::string(rsca::process::kForkMessageMax + 1, 'a'), 0));

  using rsca::process::decode_fork_reply;
  const auto pid = decode_fork_reply(encode(rsca::process::ForkReply{1234, {}}));
  REQUIRE(pid.has_value());
  CHECK(pid->pid == 1234);
  const auto error = decode_fork_reply(encode(rsca::process::ForkReply{0, "fork: no memory"}));
  REQUIRE(error.has_value());
  CHECK(error->error == "fork: no memory");
  CHECK_FALSE(decode_fork_reply("pid\0"
                                "0\0"s));
  CHECK_FALSE(decode_fork_reply("pid\0x\0"s));
}
