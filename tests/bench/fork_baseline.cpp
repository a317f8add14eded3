// rsca-bench-fork: the process-creation baselines of the launch benchmark
// (tests/bench/launch_bench.py), in C++ as the nodes create processes, not in Python:
//
//   rsca-bench-fork exec --count N -- PROGRAM [ARGS...]
//     N fork/execs of PROGRAM, started at once and each waited for: a cold launch's floor (every
//     process loads its executable and libraries);
//   rsca-bench-fork fork --count N
//     N forks of this process, started at once and each waited for, each child exiting at once:
//     the floor of a launch from fork servers (a zygote's: the executable and its libraries are
//     already loaded). The whole component runtime is linked in (CMakeLists.txt), so the process
//     forked maps what a component's fork server maps.
//
// The program runs as it runs without exec parameters: the Relay says so and exits at once (2),
// which is all a baseline of process creation needs. Prints one JSON object: {"mode", "count",
// "ms" (CLOCK_MONOTONIC from the first fork to the last child reaped), "failed" (children that
// could not be made or executed, exit 127, or were killed)}. The launch benchmark times the
// whole command from outside as well, as it times the CLI.
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "bench_common.hpp"

namespace {

// A child's exit status when it could not be executed (as a shell says it).
constexpr int kNotExecuted = 127;

struct Outcome {
  std::uint64_t ns = 0;
  std::size_t failed = 0;
};

// Starts `count` children, each running `child` (which never returns), then reaps them all.
template <typename Child>
Outcome start_and_reap(std::size_t count, Child child) {
  Outcome outcome;
  const std::uint64_t began = rsca::bench::mono_ns();
  std::size_t started = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const pid_t pid = ::fork();
    if (pid == 0)
      child();
    if (pid < 0)
      ++outcome.failed;
    else
      ++started;
  }
  for (std::size_t i = 0; i < started; ++i) {
    int status = 0;
    if (::wait(&status) < 0 || !WIFEXITED(status) || WEXITSTATUS(status) == kNotExecuted)
      ++outcome.failed;
  }
  outcome.ns = rsca::bench::mono_ns() - began;
  return outcome;
}

} // namespace

int main(int argc, char **argv) {
  CLI::App app{"rsca-bench-fork — the process-creation baselines of tests/bench/launch_bench.py"};
  app.require_subcommand(1);
  std::size_t count = 10;
  std::vector<std::string> command;
  auto *exec_cmd = app.add_subcommand("exec", "N fork/execs of a program at once, waited for");
  exec_cmd->add_option("--count", count)->check(CLI::Range(1, 100000));
  exec_cmd->add_option("command", command, "The program and its arguments")->required();
  auto *fork_cmd = app.add_subcommand("fork", "N forks of this process at once, waited for");
  fork_cmd->add_option("--count", count)->check(CLI::Range(1, 100000));
  CLI11_PARSE(app, argc, argv);

  Outcome outcome;
  if (*exec_cmd) {
    std::vector<char *> args;
    for (auto &a : command)
      args.push_back(a.data());
    args.push_back(nullptr);
    outcome = start_and_reap(count, [&args] {
      // Its output goes nowhere, as a component's goes to a log: this one's stdout is the JSON.
      if (const int null = ::open("/dev/null", O_WRONLY); null >= 0) {
        ::dup2(null, STDOUT_FILENO);
        ::dup2(null, STDERR_FILENO);
      }
      ::execv(args[0], args.data());
      ::_exit(kNotExecuted);
    });
  } else {
    outcome = start_and_reap(count, [] { ::_exit(0); });
  }
  const nlohmann::json result{{"mode", *exec_cmd ? "exec" : "fork"},
                              {"count", count},
                              {"ms", static_cast<double>(outcome.ns) / 1e6},
                              {"failed", outcome.failed}};
  std::printf("%s\n", result.dump().c_str());
  return outcome.failed == 0 ? 0 : 1;
}
