// process/spawn.hpp on real processes: what a spawned child starts with whatever this process
// has (signals, descriptors, stdin, environment, process group), and failures as error values
// naming the program with nothing started. The children are small system programs that print
// what they see into a log file; each is reaped by the test before its output is read.
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "process/spawn.hpp"
#include "temp_dir.hpp"
#include "test_files.hpp"

using namespace std::chrono_literals;
using rsca::process::Child;
using rsca::process::Command;
using rsca::process::Group;
using rsca::test::slurp;
using rsca::test::TempDir;
namespace fs = std::filesystem;

namespace {

Child start(const Command &command, Group group = Group::Own) {
  auto child = rsca::process::spawn(command, group);
  INFO((child ? std::string{} : child.error().to_string()));
  REQUIRE(child.has_value());
  REQUIRE(child->pid > 0);
  REQUIRE(child->pidfd);
  return std::move(*child);
}

// Waits for the child to exit (bounded by its pidfd) and reaps it; its exit code.
int finish(Child &child) {
  REQUIRE(rsca::process::wait_exited(child.pidfd, 10s));
  int status = 0;
  REQUIRE(::waitpid(child.pid, &status, 0) == child.pid);
  REQUIRE(WIFEXITED(status));
  return WEXITSTATUS(status);
}

// What the command prints, run to its end with its output in a log file of `dir`.
std::string output_of(const TempDir &dir, Command command) {
  command.log_file = dir.path() / "out.log";
  auto child = start(command);
  CHECK(finish(child) == 0);
  return slurp(command.log_file);
}

// The value of a "Name:\tvalue" line of /proc/PID/status as the child printed it.
std::string status_field(const std::string &status, const std::string &name) {
  std::istringstream lines(status);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind(name + ":", 0) == 0) {
      return line.substr(line.find_first_not_of(" \t", name.size() + 1));
    }
  }
  return "(no " + name + ")";
}

// The signals of a /proc signal mask ("0000000000000200": SIGUSR1), without glibc's own between
// the standard signals and SIGRTMIN (SIGCANCEL and SIGSETXID): glibc leaves those ignored in a
// child it spawns when its parent handles them, no attribute can reset them, and every glibc
// program installs its own handlers for them anyway.
std::set<int> signals_in(const std::string &mask) {
  const auto bits = std::stoull(mask, nullptr, 16);
  std::set<int> signals;
  for (int signal = 1; signal <= 64; ++signal) {
    const bool glibc_own = signal > 31 && signal < SIGRTMIN;
    if ((bits >> (signal - 1) & 1U) != 0 && !glibc_own) {
      signals.insert(signal);
    }
  }
  return signals;
}

// For its scope, this thread with SIGUSR1 ignored and SIGUSR2 blocked, as a careless parent
// (a shell's `trap '' USR1`, a daemon that blocks signals for a signalfd) would have them.
class CarelessSignals {
public:
  CarelessSignals() {
    struct sigaction ignore {};
    ignore.sa_handler = SIG_IGN;
    REQUIRE(::sigaction(SIGUSR1, &ignore, &saved_action_) == 0);
    sigset_t usr2;
    ::sigemptyset(&usr2);
    ::sigaddset(&usr2, SIGUSR2);
    REQUIRE(::pthread_sigmask(SIG_BLOCK, &usr2, &saved_mask_) == 0);
  }
  ~CarelessSignals() {
    ::pthread_sigmask(SIG_SETMASK, &saved_mask_, nullptr);
    ::sigaction(SIGUSR1, &saved_action_, nullptr);
  }
  CarelessSignals(const CarelessSignals &) = delete;
  CarelessSignals &operator=(const CarelessSignals &) = delete;

private:
  struct sigaction saved_action_ {};
  sigset_t saved_mask_{};
};

} // namespace

TEST_CASE("a spawned child has every signal's default action and none blocked", "[spawn]") {
  TempDir dir;
  const CarelessSignals careless;
  // cat reads its own status: what it was started with, before it could change anything.
  const auto status = output_of(dir, {.program = "/bin/cat", .args = {"/proc/self/status"}});
  CHECK(signals_in(status_field(status, "SigIgn")).empty());
  CHECK(signals_in(status_field(status, "SigBlk")).empty());
}

TEST_CASE("a spawned child inherits no descriptor beyond stdin, stdout and stderr", "[spawn]") {
  TempDir dir;
  // Neither close-on-exec: a plain fork and exec would hand both to the child.
  const int leaky = ::open("/dev/null", O_RDONLY);
  REQUIRE(leaky >= 0);
  const int high = ::fcntl(leaky, F_DUPFD, 100);
  REQUIRE(high >= 100);
  const auto listed = output_of(dir, {.program = "/bin/ls", .args = {"/proc/self/fd"}});
  ::close(high);
  ::close(leaky);
  // 3 is the directory ls has open while it lists it.
  CHECK(listed == "0\n1\n2\n3\n");
}

TEST_CASE("a spawned child reads /dev/null and writes to the log, appended", "[spawn]") {
  TempDir dir;
  Command command{.program = "/bin/sh",
                  .args = {"-c", "readlink /proc/$$/fd/0; echo to-stderr >&2"}};
  command.log_file = dir.path() / "logs" / "nested" / "child.log"; // folders made as needed
  for (int run = 0; run < 2; ++run) {
    auto child = start(command);
    CHECK(finish(child) == 0);
  }
  CHECK(slurp(command.log_file) == "/dev/null\nto-stderr\n/dev/null\nto-stderr\n");
}

TEST_CASE("the environment is this process's with the command's variables, the last one winning",
          "[spawn]") {
  TempDir dir;
  REQUIRE(::setenv("RSCA_SPAWN_TEST_KEPT", "kept", 1) == 0);
  REQUIRE(::setenv("RSCA_SPAWN_TEST_REPLACED", "old", 1) == 0);
  const auto printed = output_of(
      dir, {.program = "/bin/sh",
            .args = {"-c", "echo $RSCA_SPAWN_TEST_KEPT $RSCA_SPAWN_TEST_REPLACED "
                           "$RSCA_SPAWN_TEST_NEW; env | grep -c ^RSCA_SPAWN_TEST_REPLACED="},
            .env = {{"RSCA_SPAWN_TEST_REPLACED", "first"},
                    {"RSCA_SPAWN_TEST_NEW", "new"},
                    {"RSCA_SPAWN_TEST_REPLACED", "last"}}});
  ::unsetenv("RSCA_SPAWN_TEST_KEPT");
  ::unsetenv("RSCA_SPAWN_TEST_REPLACED");
  CHECK(printed == "kept last new\n1\n");
}

TEST_CASE("the arguments follow the program's path, and the working directory is the command's",
          "[spawn]") {
  TempDir dir;
  const auto printed =
      output_of(dir, {.program = "/bin/sh",
                      .args = {"-c", "echo \"$0|$1|$2\"; pwd", "zero", "one two", ""},
                      .working_dir = dir.path()});
  CHECK(printed == "zero|one two|\n" + dir.path().string() + "\n");
}

TEST_CASE("the child leads a group or a session of its own, or stays in the caller's group",
          "[spawn]") {
  const auto started = [](Group group) {
    return start({.program = "/bin/sleep", .args = {"30"}}, group);
  };
  const auto stop = [](Child &child) {
    ::kill(child.pid, SIGKILL);
    REQUIRE(::waitpid(child.pid, nullptr, 0) == child.pid);
  };
  auto own = started(Group::Own);
  CHECK(::getpgid(own.pid) == own.pid);
  CHECK(::getsid(own.pid) == ::getsid(0));
  stop(own);

  auto session = started(Group::Session);
  CHECK(::getpgid(session.pid) == session.pid);
  CHECK(::getsid(session.pid) == session.pid);
  stop(session);

  auto caller = started(Group::Caller);
  CHECK(::getpgid(caller.pid) == ::getpgrp());
  CHECK(::getsid(caller.pid) == ::getsid(0));
  stop(caller);
}

TEST_CASE("wait_exited tells a running child from one that has exited", "[spawn]") {
  auto child = start({.program = "/bin/sleep", .args = {"30"}});
  CHECK_FALSE(rsca::process::wait_exited(child.pidfd, 50ms));
  ::kill(child.pid, SIGTERM);
  CHECK(rsca::process::wait_exited(child.pidfd, 10s));
  int status = 0;
  REQUIRE(::waitpid(child.pid, &status, 0) == child.pid);
  CHECK(WIFSIGNALED(status));
}

TEST_CASE("an exec that fails is an error naming the program, and leaves no child", "[spawn]") {
  TempDir dir;
  const auto error_of = [](const Command &command) {
    auto child = rsca::process::spawn(command, Group::Own);
    REQUIRE_FALSE(child.has_value());
    REQUIRE(child.error().diagnostics().size() == 1);
    const auto &diagnostic = child.error().diagnostics().front();
    CHECK(diagnostic.where.file == command.program.string());
    CHECK(diagnostic.rule == "execute");
    // Every child failed to start is reaped: nothing of it is left to wait for.
    CHECK(::waitpid(-1, nullptr, WNOHANG) == -1);
    CHECK(errno == ECHILD);
    return diagnostic.message;
  };

  // Found only by the exec itself: the file is an executable regular file, but no program.
  const auto garbage = dir.path() / "garbage";
  std::ofstream(garbage) << "\x01\x02 not a program\n";
  fs::permissions(garbage, fs::perms::owner_all);
  CHECK(error_of({.program = garbage}) ==
        "cannot execute " + garbage.string() + ": not an executable format");

  const auto no_interpreter = dir.path() / "no_interpreter.sh";
  std::ofstream(no_interpreter) << "#!/nonexistent/rsca/interpreter\n";
  fs::permissions(no_interpreter, fs::perms::owner_all);
  CHECK(error_of({.program = no_interpreter}) ==
        "cannot execute " + no_interpreter.string() + ": no such file");

  // Found before anything starts.
  CHECK(error_of({.program = "/nonexistent/rsca/program"}) ==
        "cannot execute /nonexistent/rsca/program: no such file");
  CHECK(error_of({.program = "sh"}) == "cannot execute sh: no such file"); // no PATH search
  CHECK(error_of({.program = "/bin/true", .working_dir = dir.path() / "missing"}) ==
        "cannot use working directory " + (dir.path() / "missing").string() +
            ": no such directory");
  CHECK(error_of({.program = "/bin/true", .env = {{"", "x"}}}) ==
        "invalid environment variable name \"\"");
  CHECK(error_of({.program = "/bin/true", .log_file = dir.path() / "garbage" / "x.log"})
            .rfind("cannot create the directory of log file", 0) == 0);
}

namespace {

// The credentials of `user`, which must exist on the test host (nobody does on Debian).
rsca::process::Credentials user_named(const std::string &user) {
  auto credentials = rsca::process::credentials_of(user);
  REQUIRE(credentials.has_value());
  return *credentials;
}

// For its scope, this process's soft limit of descriptors at `limit`.
class DescriptorLimit {
public:
  explicit DescriptorLimit(rlim_t limit) {
    REQUIRE(::getrlimit(RLIMIT_NOFILE, &saved_) == 0);
    rlimit lowered = saved_;
    lowered.rlim_cur = limit;
    REQUIRE(::setrlimit(RLIMIT_NOFILE, &lowered) == 0);
  }
  ~DescriptorLimit() { ::setrlimit(RLIMIT_NOFILE, &saved_); }
  DescriptorLimit(const DescriptorLimit &) = delete;
  DescriptorLimit &operator=(const DescriptorLimit &) = delete;

private:
  rlimit saved_{};
};

} // namespace

TEST_CASE("a child given a user runs as that user, with its groups and nothing else of this "
          "process's",
          "[spawn]") {
  INFO("only root may start a process as another user: the tests run as root");
  REQUIRE(::geteuid() == 0);
  TempDir dir;
  fs::permissions(dir.path(), fs::perms::all); // the user writes nothing here, but may enter
  const auto nobody = user_named("nobody");
  const CarelessSignals careless;
  const int leaky = ::open("/dev/null", O_RDONLY);
  REQUIRE(leaky >= 0);
  const auto status = output_of(dir, {.program = "/bin/cat",
                                      .args = {"/proc/self/status"},
                                      .working_dir = dir.path(),
                                      .user = nobody});
  const auto uid = std::to_string(nobody.uid);
  const auto gid = std::to_string(nobody.gid);
  CHECK(status_field(status, "Uid") == fmt::format("{0}\t{0}\t{0}\t{0}", uid));
  CHECK(status_field(status, "Gid") == fmt::format("{0}\t{0}\t{0}\t{0}", gid));
  // nobody's only group, root's gone ("Groups:" ends with a blank).
  CHECK(status_field(status, "Groups") == gid + " ");
  CHECK(status_field(status, "CapEff") == "0000000000000000");
  CHECK(signals_in(status_field(status, "SigIgn")).empty());
  CHECK(signals_in(status_field(status, "SigBlk")).empty());
  // Its descriptors are a spawned child's: stdin, its log, the one it is given.
  const TempDir other; // a log of its own
  const auto listed = output_of(
      other,
      {.program = "/bin/ls", .args = {"/proc/self/fd"}, .inherit = {{leaky, 5}}, .user = nobody});
  ::close(leaky);
  CHECK(listed == "0\n1\n2\n3\n5\n");
  auto group = start({.program = "/bin/sleep", .args = {"30"}, .user = nobody});
  CHECK(::getpgid(group.pid) == group.pid);
  ::kill(group.pid, SIGKILL);
  REQUIRE(::waitpid(group.pid, nullptr, 0) == group.pid);
}

TEST_CASE("a child that cannot take its user's working directory is an error naming the step, "
          "and leaves no child",
          "[spawn]") {
  INFO("only root may start a process as another user: the tests run as root");
  REQUIRE(::geteuid() == 0);
  TempDir dir; // mkdtemp's 0700: nobody may not enter it
  auto child = rsca::process::spawn(
      {.program = "/bin/true", .working_dir = dir.path(), .user = user_named("nobody")},
      Group::Own);
  REQUIRE_FALSE(child.has_value());
  const std::string message = child.error().diagnostics().front().message;
  CHECK(message.rfind("cannot execute /bin/true as user nobody: chdir: permission denied", 0) == 0);
  CHECK(message.find("chmod o+x") != std::string::npos); // and what to do about it
  CHECK(::waitpid(-1, nullptr, WNOHANG) == -1);
}

TEST_CASE("a process under a limit of 64 descriptors hands a child its descriptors", "[spawn]") {
  TempDir dir;
  const int given = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  REQUIRE(given >= 0);
  std::string listed;
  {
    const DescriptorLimit limit(64);
    listed =
        output_of(dir, {.program = "/bin/ls", .args = {"/proc/self/fd"}, .inherit = {{given, 4}}});
  }
  ::close(given);
  CHECK(listed == "0\n1\n2\n3\n4\n");
}
