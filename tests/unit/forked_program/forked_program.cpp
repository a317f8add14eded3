// A program that serves forks (process/fork_service.hpp) and, in each process it starts, says what
// it was given, for fork_server_test: its arguments, working directory, a variable, its process
// group and parent, its CPUs, what its standard input and descriptors 3 and 4 are. Exits with the
// code its first argument gives, or waits for a signal when that is "wait". Test-only.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include <fcntl.h>
#include <sched.h>
#include <unistd.h>

#include "process/fork_request.hpp"
#include "process/fork_service.hpp"

int main(int argc, char **argv) {
  rsca::process::serve_forks_if_asked(argc, argv, rsca::process::kForkServerReady);
  std::string line = "args:";
  for (int i = 1; i < argc; ++i)
    line += std::string(" ") + argv[i];
  std::printf("%s\n", line.c_str());
  char cwd[4096] = "";
  std::printf("cwd: %s\n", ::getcwd(cwd, sizeof cwd) != nullptr ? cwd : "?");
  const char *value = std::getenv("RSCA_TEST_VALUE");
  std::printf("value: %s\n", value != nullptr ? value : "(unset)");
  std::printf("server variable: %s\n",
              std::getenv(rsca::process::kForkServerVariable) != nullptr ? "set" : "unset");
  std::printf("group: %s\n", ::getpgid(0) == ::getpid() ? "own" : "other");
  std::printf("parent: %d\n", static_cast<int>(::getppid()));
  cpu_set_t cpus;
  CPU_ZERO(&cpus);
  ::sched_getaffinity(0, sizeof cpus, &cpus);
  std::printf("cpus: %d\n", CPU_COUNT(&cpus));
  char byte = 0;
  std::printf("stdin: %s\n", ::read(STDIN_FILENO, &byte, 1) == 0 ? "empty" : "not empty");
  std::printf("fd 4: %s\n", ::fcntl(4, F_GETFD) < 0 ? "closed" : "open");
  std::fflush(stdout);
  const char through[] = "through 3\n";
  if (::write(3, through, std::strlen(through)) < 0)
    std::printf("fd 3: closed\n");
  std::fflush(stdout);
  if (argc > 1 && std::strcmp(argv[1], "wait") == 0)
    for (;;)
      ::pause();
  return argc > 1 ? std::atoi(argv[1]) : 0;
}
