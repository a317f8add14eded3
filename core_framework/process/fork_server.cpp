// process/fork_server.hpp: starting a fork server, a request with its descriptors, and the reply.
#include "process/fork_server.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <functional>
#include <string_view>

#include <fcntl.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <fmt/format.h>

#include "process/fork_request.hpp"

namespace rsca::process {
namespace {

tl::unexpected<Error> fork_error(const std::filesystem::path &program, std::string message) {
  return make_error({program.string(), 0, 0}, "execute", std::move(message));
}

// A whole message within `timeout`; empty when none came (the server closed its end, or is
// silent).
std::optional<std::string> receive(const Fd &socket, std::chrono::milliseconds timeout) {
  pollfd ready{socket.get(), POLLIN, 0};
  int polled = 0;
  do {
    polled = ::poll(&ready, 1, static_cast<int>(timeout.count()));
  } while (polled < 0 && errno == EINTR);
  if (polled != 1)
    return std::nullopt;
  std::string buffer(kForkMessageMax, '\0');
  const auto size = ::recv(socket.get(), buffer.data(), buffer.size(), MSG_DONTWAIT);
  if (size <= 0)
    return std::nullopt;
  buffer.resize(static_cast<std::size_t>(size));
  return buffer;
}

// The CPUs a process this thread spawned would inherit (the GPP sets them for a placement).
std::vector<unsigned> calling_thread_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  std::vector<unsigned> cpus;
  if (::sched_getaffinity(0, sizeof set, &set) != 0)
    return cpus;
  for (unsigned cpu = 0; cpu < CPU_SETSIZE; ++cpu)
    if (CPU_ISSET(cpu, &set))
      cpus.push_back(cpu);
  return cpus;
}

bool send_request(const Fd &socket, const std::string &message, const std::vector<int> &fds) {
  iovec io{const_cast<char *>(message.data()), message.size()};
  msghdr header{};
  header.msg_iov = &io;
  header.msg_iovlen = 1;
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(int) * kForkFdsMax)]{};
  if (!fds.empty()) {
    header.msg_control = control;
    header.msg_controllen = CMSG_SPACE(sizeof(int) * fds.size());
    auto *cmsg = CMSG_FIRSTHDR(&header);
    cmsg->cmsg_level = SOL_SOCKET;
    cmsg->cmsg_type = SCM_RIGHTS;
    cmsg->cmsg_len = CMSG_LEN(sizeof(int) * fds.size());
    std::memcpy(CMSG_DATA(cmsg), fds.data(), sizeof(int) * fds.size());
  }
  ssize_t sent = 0;
  do {
    sent = ::sendmsg(socket.get(), &header, MSG_NOSIGNAL);
  } while (sent < 0 && errno == EINTR);
  return sent == static_cast<ssize_t>(message.size());
}

} // namespace

bool may_serve_forks(const std::filesystem::path &program) {
  const Fd file{::open(program.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK)}; // a FIFO: no wait
  struct stat status {};
  if (!file || ::fstat(file.get(), &status) != 0 || !S_ISREG(status.st_mode) || status.st_size <= 0)
    return false;
  const auto size = static_cast<std::size_t>(status.st_size);
  void *bytes = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, file.get(), 0);
  if (bytes == MAP_FAILED)
    return false;
  const std::string_view all(static_cast<const char *>(bytes), size);
  const std::boyer_moore_horspool_searcher searcher(kForkServerReady.begin(),
                                                    kForkServerReady.end());
  const bool found = std::search(all.begin(), all.end(), searcher) != all.end();
  ::munmap(bytes, size);
  return found;
}

Expected<ForkServer> ForkServer::start(const std::filesystem::path &program,
                                       const std::vector<std::pair<std::string, std::string>> &env,
                                       std::chrono::milliseconds timeout,
                                       const std::optional<Credentials> &user) {
  int ends[2];
  if (::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, ends) != 0)
    return fork_error(program, fmt::format("cannot start a fork server of {}: socketpair: {}",
                                           program.string(), errno_text(errno)));
  Fd ours{ends[0]};
  Fd theirs{ends[1]};
  Command command{.program = program, .args = {"--rsca-fork-server"}, .env = env};
  // Room for the started processes' command lines where the kernel does not let them point
  // /proc/PID/cmdline elsewhere (fork_service.cpp).
  command.args.emplace_back(4096, ' ');
  command.env.emplace_back(kForkServerVariable, std::to_string(kForkServerFd));
  command.inherit.push_back({theirs.get(), kForkServerFd});
  command.user = user;
  auto child = process::spawn(command, Group::Own);
  if (!child)
    return tl::unexpected(std::move(child.error()));
  theirs.reset();
  ForkServer server(std::move(*child), std::move(ours));
  const auto ready = receive(server.socket_, timeout);
  if (!ready || *ready != kForkServerReady) {
    server.stop();
    return fork_error(program, fmt::format("{} does not serve forks (no answer within {} ms)",
                                           program.string(), timeout.count()));
  }
  return server;
}

ForkServer &ForkServer::operator=(ForkServer &&other) noexcept {
  if (this != &other) {
    stop();
    server_ = std::move(other.server_);
    socket_ = std::move(other.socket_);
  }
  return *this;
}

ForkServer::~ForkServer() {
  stop();
}

void ForkServer::stop() {
  socket_.reset();
  if (!server_.pidfd)
    return;
  // The server's whole group: a middle process it had forked goes with it (re-parented here, as
  // this process is a child subreaper, and reaped below with the server).
  ::kill(-server_.pid, SIGKILL);
  while (::waitpid(server_.pid, nullptr, 0) < 0 && errno == EINTR) {
  }
  siginfo_t info{};
  while (::waitid(P_PGID, static_cast<id_t>(server_.pid), &info, WEXITED | WNOHANG) == 0 &&
         info.si_pid != 0)
    info = {};
  server_.pidfd.reset();
}

Expected<Child> ForkServer::spawn(const Command &command, std::chrono::milliseconds timeout) {
  auto log = prepare_to_spawn(command);
  if (!log)
    return tl::unexpected(std::move(log.error()));
  if (!alive())
    return fork_error(command.program, "its fork server has stopped");
  ForkRequest request{.program = command.program.string(),
                      .args = command.args,
                      .env = command.env,
                      .working_dir = command.working_dir.string(),
                      .cpus = calling_thread_cpus(),
                      .log = static_cast<bool>(*log),
                      .fd_numbers = {}};
  std::vector<int> fds;
  if (*log)
    fds.push_back(log->get());
  for (const auto &inherited : command.inherit) {
    fds.push_back(inherited.fd);
    request.fd_numbers.push_back(inherited.as);
  }
  const auto message = encode(request);
  if (fds.size() > kForkFdsMax || message.size() > kForkMessageMax)
    return fork_error(command.program, "too many descriptors or too long a command for its "
                                       "fork server");
  std::optional<std::string> answer;
  if (send_request(socket_, message, fds))
    answer = receive(socket_, timeout);
  if (!answer) {
    stop();
    return fork_error(command.program,
                      fmt::format("its fork server did not answer within {} ms", timeout.count()));
  }
  auto reply = decode_fork_reply(*answer);
  if (!reply || !reply->error.empty())
    return fork_error(command.program, fmt::format("its fork server cannot start it: {}",
                                                   reply ? reply->error : reply.error()));
  Child started{reply->pid, open_pidfd(reply->pid)};
  if (!started.pidfd) {
    const int error = errno;
    ::kill(-reply->pid, SIGKILL);
    ::waitpid(reply->pid, nullptr, 0);
    return fork_error(command.program, fmt::format("cannot watch pid {}: pidfd_open: {}",
                                                   reply->pid, errno_text(error)));
  }
  return started;
}

} // namespace rsca::process
