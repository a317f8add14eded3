// process/fork_service.hpp: the fork server's loop, the double fork, and what the started process
// takes from its request before it returns to main.
#include "process/fork_service.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <fcntl.h>
#include <poll.h>
#include <sched.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include "process/fd.hpp"
#include "process/fork_request.hpp"

namespace rsca::process {
namespace {

// The fork server's own argument area, [begin, end): where a started process writes its command
// line when the kernel does not let it point /proc/PID/cmdline elsewhere.
struct ArgumentArea {
  char *begin = nullptr;
  char *end = nullptr;
};

struct Received {
  std::string message;
  std::vector<Fd> fds;
  bool truncated = false;
};

// What the middle process tells the server: the started process's pid, or the step that failed
// and its errno. One write of less than PIPE_BUF: whole or not at all.
struct Report {
  pid_t pid = 0;
  int error = 0;
  char step[32] = {};
};

Report failure(const char *step, int error) {
  Report report;
  report.error = error;
  std::strncpy(report.step, step, sizeof report.step - 1);
  return report;
}

void write_report(int fd, const Report &report) {
  [[maybe_unused]] const auto written = ::write(fd, &report, sizeof report);
}

// A report from `fd`; a failure at `step` when the writer went without one.
Report read_report(int fd, const char *step) {
  Report report;
  ssize_t size = 0;
  do {
    size = ::read(fd, &report, sizeof report);
  } while (size < 0 && errno == EINTR);
  return size == static_cast<ssize_t>(sizeof report) ? report : failure(step, EIO);
}

// What a started process continues with: its request, its descriptors, and the middle process
// whose exit re-parents it to the node.
struct Started {
  ForkRequest request;
  std::vector<Fd> fds;
  pid_t middle = 0;
};

void send_message(int socket, std::string_view message) {
  while (::send(socket, message.data(), message.size(), MSG_NOSIGNAL) < 0 && errno == EINTR) {
  }
}

// The next request; nullopt once the node has closed its end (or the socket failed).
std::optional<Received> receive(int socket) {
  std::string buffer(kForkMessageMax + 1, '\0');
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(int) * kForkFdsMax)];
  iovec io{buffer.data(), buffer.size()};
  msghdr header{};
  header.msg_iov = &io;
  header.msg_iovlen = 1;
  header.msg_control = control;
  header.msg_controllen = sizeof control;
  ssize_t size = 0;
  do {
    size = ::recvmsg(socket, &header, MSG_CMSG_CLOEXEC);
  } while (size < 0 && errno == EINTR);
  if (size <= 0)
    return std::nullopt;
  Received received;
  for (auto *cmsg = CMSG_FIRSTHDR(&header); cmsg != nullptr; cmsg = CMSG_NXTHDR(&header, cmsg)) {
    if (cmsg->cmsg_level != SOL_SOCKET || cmsg->cmsg_type != SCM_RIGHTS)
      continue;
    const std::size_t count = (cmsg->cmsg_len - CMSG_LEN(0)) / sizeof(int);
    for (std::size_t i = 0; i < count; ++i) {
      int fd = -1;
      std::memcpy(&fd, CMSG_DATA(cmsg) + i * sizeof(int), sizeof fd);
      received.fds.emplace_back(fd);
    }
  }
  received.truncated = (header.msg_flags & (MSG_TRUNC | MSG_CTRUNC)) != 0 ||
                       static_cast<std::size_t>(size) > kForkMessageMax;
  received.message.assign(buffer.data(), static_cast<std::size_t>(size));
  return received;
}

// In the middle process: what the started process inherits and may fail (its directory, its
// CPUs); the failed step, or none. System calls only: the middle process is on the server's
// critical path, and what it wrote to memory it would copy (copy-on-write) before it forks.
const char *take_place(const ForkRequest &request) {
  if (!request.working_dir.empty() && ::chdir(request.working_dir.c_str()) != 0)
    return "chdir";
  if (!request.cpus.empty()) {
    cpu_set_t set;
    CPU_ZERO(&set);
    for (const unsigned cpu : request.cpus)
      CPU_SET(cpu, &set);
    cpu_set_t now; // most requests ask for the server's own CPUs, the node's: nothing to do
    const bool same = ::sched_getaffinity(0, sizeof now, &now) == 0 && CPU_EQUAL(&now, &set);
    if (!same && ::sched_setaffinity(0, sizeof set, &set) != 0)
      return "sched_setaffinity";
  }
  return nullptr;
}

// In the middle process: takes what may fail for the started process, which inherits it, forks
// it, tells the server through `to_server`, and exits. Returns only in the started process: the
// middle process's pid. A process the node is told of has started, as with spawn.
pid_t fork_from_middle(const ForkRequest &request, int to_server) {
  if (const char *failed = take_place(request)) {
    write_report(to_server, failure(failed, errno));
    ::_exit(0);
  }
  const pid_t middle = ::getpid();
  const pid_t child = ::fork();
  if (child == 0)
    return middle;
  if (child < 0) {
    write_report(to_server, failure("fork", errno));
    ::_exit(0);
  }
  // Its process group exists before the node learns its pid (it sets it too: either may run
  // first), so that the node can signal the group at once.
  ::setpgid(child, child);
  Report report;
  report.pid = child;
  write_report(to_server, report);
  ::_exit(0);
}

// Serves requests; returns only in a started process. The server exits when the node has gone.
Started serve(int socket, std::string_view ready) {
  send_message(socket, ready);
  for (;;) {
    auto received = receive(socket);
    if (!received)
      ::_exit(0);
    auto request = received->truncated
                       ? tl::unexpected(std::string("message over the size bounds"))
                       : decode_fork_request(received->message, received->fds.size());
    if (!request) {
      send_message(socket, encode(ForkReply{0, "bad request: " + request.error()}));
      continue;
    }
    int pipe_ends[2];
    if (::pipe2(pipe_ends, O_CLOEXEC) != 0) {
      send_message(socket, encode(ForkReply{0, std::string("pipe: ") + std::strerror(errno)}));
      continue;
    }
    Fd read_end{pipe_ends[0]};
    Fd write_end{pipe_ends[1]};
    const pid_t middle = ::fork();
    if (middle == 0) {
      read_end.reset();
      const pid_t parent = fork_from_middle(*request, write_end.get());
      return Started{std::move(*request), std::move(received->fds), parent};
    }
    write_end.reset();
    Report report = middle < 0 ? failure("fork", errno) : read_report(read_end.get(), "fork");
    if (middle > 0)
      while (::waitpid(middle, nullptr, 0) < 0 && errno == EINTR) {
      }
    send_message(socket, encode(report.error == 0 ? ForkReply{report.pid, {}}
                                                  : ForkReply{0, std::string(report.step) + ": " +
                                                                     std::strerror(report.error)}));
  }
}

// A started process that cannot take its variables or descriptors (out of memory: a failure no
// test has made happen) says so in its log, or the node's, and exits as a failed exec would.
[[noreturn]] void fail(const char *step) {
  const int error = errno;
  std::fprintf(stderr, "fork server: cannot start the process: %s: %s\n", step,
               std::strerror(error));
  ::_exit(127);
}

// stdin from /dev/null, stdout and stderr to the log, each inherited descriptor as its number,
// and no other descriptor (the server's socket among them).
void take_descriptors(const Started &started, std::vector<Fd> &fds) {
  const ForkRequest &request = started.request;
  std::set<int> given(request.fd_numbers.begin(), request.fd_numbers.end());
  // Each descriptor first goes above every number it is given as, so giving one its number
  // cannot close another not given yet.
  const int above = given.empty() ? STDERR_FILENO + 1 : *given.rbegin() + 1;
  std::vector<int> moved;
  for (auto &fd : fds) {
    moved.push_back(::fcntl(fd.get(), F_DUPFD, above));
    if (moved.back() < 0)
      fail("fcntl");
  }
  const int null = ::open("/dev/null", O_RDONLY);
  if (null < 0 || ::dup2(null, STDIN_FILENO) < 0)
    fail("/dev/null");
  std::size_t next = 0;
  if (request.log) {
    if (::dup2(moved[0], STDOUT_FILENO) < 0 || ::dup2(moved[0], STDERR_FILENO) < 0)
      fail("dup2");
    next = 1;
  }
  for (const int number : request.fd_numbers)
    if (::dup2(moved[next++], number) < 0)
      fail("dup2");
  for (int fd = STDERR_FILENO + 1; fd < above; ++fd)
    if (given.count(fd) == 0)
      ::close(fd);
  ::closefrom(above);
  for (auto &fd : fds) // already closed above: forget them without closing again
    [[maybe_unused]] const int released = fd.release();
}

// /proc/PID/cmdline says the started process's arguments: pointed at a copy where the kernel lets
// a process do that (CAP_SYS_RESOURCE), else written over the fork server's own (cut to fit; the
// rest of that room reads as empty arguments).
void take_command_line(const std::string &program, const std::vector<std::string> &args,
                       ArgumentArea area) {
  static std::string line; // the process's for the rest of its life
  line = program;
  line.push_back('\0');
  for (const auto &arg : args) {
    line += arg;
    line.push_back('\0');
  }
  const auto begin = reinterpret_cast<unsigned long>(line.data());
  if (::prctl(PR_SET_MM, PR_SET_MM_ARG_START, begin, 0, 0) == 0 &&
      ::prctl(PR_SET_MM, PR_SET_MM_ARG_END, begin + line.size(), 0, 0) == 0)
    return;
  const auto room = static_cast<std::size_t>(area.end - area.begin);
  std::memset(area.begin, 0, room);
  std::memcpy(area.begin, line.data(), std::min(room > 0 ? room - 1 : 0, line.size()));
}

// Once the middle process has exited, the started process is the node's child (the node is a
// child subreaper): what it checks before it runs (component/process.cpp's die_with_node).
void wait_until_adopted(pid_t middle) {
  if (::getppid() != middle)
    return;
  Fd pidfd{static_cast<int>(::syscall(SYS_pidfd_open, middle, 0))};
  pollfd exited{pidfd.get(), POLLIN, 0};
  if (pidfd)
    ::poll(&exited, 1, 5000);
}

// The started process takes the rest of its request (its middle process took what it inherits);
// the new argv lives for the rest of its life.
void become(Started &started, ArgumentArea area, int &argc, char **&argv) {
  static std::vector<std::string> arguments;
  static std::vector<char *> pointers;
  const ForkRequest &request = started.request;
  const std::string program = request.program.empty() ? argv[0] : request.program;
  if (::setpgid(0, 0) != 0)
    fail("setpgid");
  for (const auto &[name, value] : started.request.env)
    if (::setenv(name.c_str(), value.c_str(), 1) != 0)
      fail("setenv");
  take_descriptors(started, started.fds);
  take_command_line(program, request.args, area);
  arguments.assign({program});
  arguments.insert(arguments.end(), request.args.begin(), request.args.end());
  for (auto &argument : arguments)
    pointers.push_back(argument.data());
  pointers.push_back(nullptr);
  argc = static_cast<int>(arguments.size());
  argv = pointers.data();
  wait_until_adopted(started.middle);
}

} // namespace

void serve_forks_if_asked(int &argc, char **&argv, std::string_view ready) {
  const char *variable = std::getenv(kForkServerVariable);
  if (variable == nullptr || argc < 1)
    return;
  const int socket = std::atoi(variable);
  ::unsetenv(kForkServerVariable);    // not for the processes it starts
  ::prctl(PR_SET_PDEATHSIG, SIGKILL); // cleared in what it forks
  ArgumentArea area{argv[0], argv[argc - 1] + std::strlen(argv[argc - 1]) + 1};
  Started started = serve(socket, ready);
  become(started, area, argc, argv);
}

} // namespace rsca::process
