// A program that serves forks (process/fork_service.hpp) and, in each process it starts, says what
// it was given, for fork_server_test: its arguments, working directory, a variable, its process
// group and parent, its CPUs, what its standard input and descriptors 3 and 4 are, every
// descriptor it has, and the signals it ignores or blocks. Exits with the code its first argument
// gives, or waits for a signal when that is "wait". Test-only.
#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <dirent.h>
#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <unistd.h>

#include "process/fork_request.hpp"
#include "process/fork_service.hpp"

namespace {

// Its open descriptors, "0 1 2 ...", without the one that lists them.
std::string descriptors() {
  std::string listed;
  DIR *dir = ::opendir("/proc/self/fd");
  if (dir == nullptr)
    return "?";
  std::vector<int> fds;
  while (const dirent *entry = ::readdir(dir))
    if (entry->d_name[0] != '.' && std::atoi(entry->d_name) != ::dirfd(dir))
      fds.push_back(std::atoi(entry->d_name));
  ::closedir(dir);
  std::sort(fds.begin(), fds.end());
  for (const int fd : fds)
    listed += (listed.empty() ? "" : " ") + std::to_string(fd);
  return listed;
}

// The signals whose action is to be ignored, or that are blocked, "none" when none is. glibc's
// own (between the standard signals and SIGRTMIN) cannot be asked about: sigaction refuses them.
std::string signals(bool blocked) {
  sigset_t mask;
  ::sigemptyset(&mask);
  ::pthread_sigmask(SIG_BLOCK, nullptr, &mask);
  std::string listed;
  for (int signal = 1; signal <= SIGRTMAX; ++signal) {
    struct sigaction action {};
    if (::sigaction(signal, nullptr, &action) != 0)
      continue;
    const bool listed_here =
        blocked ? ::sigismember(&mask, signal) == 1 : action.sa_handler == SIG_IGN;
    if (listed_here)
      listed += (listed.empty() ? "" : " ") + std::to_string(signal);
  }
  return listed.empty() ? "none" : listed;
}

} // namespace

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
  std::printf("descriptors: %s\n", descriptors().c_str());
  std::printf("ignored signals: %s\n", signals(false).c_str());
  std::printf("blocked signals: %s\n", signals(true).c_str());
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
