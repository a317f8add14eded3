// rsca-bench-rangestop-tcp: the RangeStop experiment over plain TCP between two processes, the
// second way of tests/bench/rangestop_bench.py. Loopback, TCP_NODELAY, POSIX sockets.
//
//   rsca-bench-rangestop-tcp --role controller [--port P] [--address A]   listens on A (default
//       127.0.0.1; port 0: any), prints {"listening": PORT}, serves one robot until it hangs up
//   rsca-bench-rangestop-tcp --role robot --port P [--address A] [--runs N ...]   the runs (JSON
//       lines); A: the controller's address (another network host's, for --hosts)
//
// The robot steps the world in real time, reads the range every period and sends it with its
// timestamp and the run's number; the controller answers every reading with a command carrying
// the reading's timestamp and run (StopCrash's decision, latched; a new run number unlatches it,
// as StopCrash.start() does); the robot applies each command of the current run to the world and
// measures its delay as it arrives. Output and shared rules: rangestop_common.hpp.
// Exit 0, 1 when a run or the connection failed, 2 on bad usage.
#include "rangestop_common.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace {

using namespace rsca::bench::rangestop;
constexpr const char *kProgram = "rsca-bench-rangestop-tcp";
constexpr const char *kWay = "tcp";

// Both messages: run number, reading timestamp (ns), a value (the range, or the commanded
// speed), in host byte order (both ends are on one host).
struct Message {
  std::uint32_t run = 0;
  std::uint64_t timestamp_ns = 0;
  double value = 0.0;
};
constexpr std::size_t kMessageSize = 4 + 8 + 8;

void encode(const Message &m, unsigned char *out) {
  std::memcpy(out, &m.run, 4);
  std::memcpy(out + 4, &m.timestamp_ns, 8);
  std::memcpy(out + 12, &m.value, 8);
}

Message decode(const unsigned char *in) {
  Message m;
  std::memcpy(&m.run, in, 4);
  std::memcpy(&m.timestamp_ns, in + 4, 8);
  std::memcpy(&m.value, in + 12, 8);
  return m;
}

std::string last_error(const char *what) {
  return std::string(what) + ": " + std::strerror(errno);
}

bool send_message(int fd, const Message &m) {
  unsigned char buffer[kMessageSize];
  encode(m, buffer);
  std::size_t sent = 0;
  while (sent < kMessageSize) {
    const ssize_t n = ::send(fd, buffer + sent, kMessageSize - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0)
      return false;
    sent += static_cast<std::size_t>(n);
  }
  return true;
}

// One whole message; false on end of stream or error.
bool receive_message(int fd, Message &m) {
  unsigned char buffer[kMessageSize];
  std::size_t got = 0;
  while (got < kMessageSize) {
    const ssize_t n = ::recv(fd, buffer + got, kMessageSize - got, 0);
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0)
      return false;
    got += static_cast<std::size_t>(n);
  }
  m = decode(buffer);
  return true;
}

void no_delay(int fd) {
  const int one = 1;
  if (::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one) != 0)
    die(kProgram, last_error("TCP_NODELAY"));
}

// The controller's IPv4 address (loopback unless --address says otherwise).
in_addr g_address{htonl(INADDR_LOOPBACK)};

sockaddr_in controller_address(std::uint16_t port) {
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(port);
  address.sin_addr = g_address;
  return address;
}

// The controller: one robot, every reading answered, until the robot hangs up.
int controller(const Settings &s, std::uint16_t port) {
  const int listener = ::socket(AF_INET, SOCK_STREAM, 0);
  if (listener < 0)
    die(kProgram, last_error("socket"));
  const int one = 1;
  ::setsockopt(listener, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  auto address = controller_address(port);
  if (::bind(listener, reinterpret_cast<sockaddr *>(&address), sizeof address) != 0)
    die(kProgram, last_error("bind"));
  if (::listen(listener, 1) != 0)
    die(kProgram, last_error("listen"));
  socklen_t length = sizeof address;
  if (::getsockname(listener, reinterpret_cast<sockaddr *>(&address), &length) != 0)
    die(kProgram, last_error("getsockname"));
  std::cout << nlohmann::json{{"listening", ntohs(address.sin_port)}}.dump() << std::endl;

  const int fd = ::accept(listener, nullptr, nullptr);
  if (fd < 0)
    die(kProgram, last_error("accept"));
  ::close(listener);
  no_delay(fd);
  StopCrash stop_crash(s);
  std::uint32_t run = 0;
  bool started = false;
  Message m;
  std::uint64_t answered = 0;
  while (receive_message(fd, m)) {
    if (!started || m.run != run) { // a new run: StopCrash.start()
      stop_crash.start();
      run = m.run;
      started = true;
    }
    m.value = stop_crash.on_range(m.value); // timestamp and run go back as they came
    if (!send_message(fd, m))
      die(kProgram, last_error("sending a command"));
    ++answered;
  }
  ::close(fd);
  std::cerr << kProgram << ": controller answered " << answered << " readings\n";
  return 0;
}

int connect_to(std::uint16_t port) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  for (;;) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0)
      die(kProgram, last_error("socket"));
    auto address = controller_address(port);
    if (::connect(fd, reinterpret_cast<sockaddr *>(&address), sizeof address) == 0) {
      no_delay(fd);
      return fd;
    }
    const auto error = last_error("connect");
    ::close(fd);
    if (std::chrono::steady_clock::now() > deadline)
      die(kProgram, error);
    std::this_thread::sleep_for(std::chrono::milliseconds(50)); // pacing a retry
  }
}

// One run on the robot's side; false when the connection failed.
bool robot_run(const Settings &s, int fd, std::uint32_t run) {
  const std::uint64_t seed = s.first_seed + run;
  auto created = rsca::sim::World::create(scenario(s, seed));
  if (!created)
    die(kProgram, created.error().to_string());
  PacedWorld paced(std::move(*created));
  auto &world = paced.world();
  Delays delays;
  std::atomic<bool> stop_commanded{false};
  std::atomic<bool> failed{false};
  std::atomic<double> stop_range{0.0};
  std::uint64_t readings = 0;
  {
    // The drive: commands of this run (earlier runs' late answers are dropped), delay first.
    std::jthread drive([&](std::stop_token stop) {
      pollfd p{fd, POLLIN, 0};
      while (!stop.stop_requested()) {
        const int ready = ::poll(&p, 1, 20);
        if (ready < 0 && errno == EINTR)
          continue;
        if (ready < 0 || (ready > 0 && (p.revents & (POLLERR | POLLHUP | POLLNVAL)) != 0 &&
                          (p.revents & POLLIN) == 0)) {
          failed = true;
          return;
        }
        if (ready == 0)
          continue;
        Message m;
        if (!receive_message(fd, m)) {
          failed = true;
          return;
        }
        if (m.run != run)
          continue;
        delays.record(m.timestamp_ns, now_ns());
        if (m.value == 0.0)
          stop_commanded = true;
        world.set_velocity(m.value, 0.0);
      }
    });
    // The sensor.
    std::jthread sensor([&](std::stop_token stop) {
      every(stop, std::chrono::milliseconds(s.period_ms), [&] {
        const auto state = world.snapshot();
        Message m{run, now_ns(), state.ranges[0].range};
        if (m.value < s.threshold && stop_range.load() == 0.0)
          stop_range = m.value; // the reading the controller stops on
        ++readings;
        if (!send_message(fd, m))
          failed = true;
      });
    });
    const bool rested = wait_for_rest(
        world, s, [&] { return stop_commanded.load(); }, [&] { return failed.load(); });
    if (failed.load())
      return false;
    if (!rested)
      die(kProgram, "run " + std::to_string(run) + ": the robot did not come to rest");
  }
  print_run(kWay, run, seed, world, stop_range.load(), readings, delays.take());
  return true;
}

int robot(const Settings &s, std::uint16_t port) {
  const int fd = connect_to(port);
  print_header(kWay, s);
  for (std::uint32_t run = 0; run < s.runs; ++run) {
    if (!robot_run(s, fd, run)) {
      ::close(fd);
      die(kProgram, "run " + std::to_string(run) + ": the connection to the controller failed");
    }
  }
  ::shutdown(fd, SHUT_WR);
  ::close(fd);
  return 0;
}

} // namespace

int main(int argc, char **argv) {
  CLI::App app{"The RangeStop experiment over plain TCP between two processes, real time"};
  Settings settings;
  std::string role;
  std::uint16_t port = 0;
  add_options(app, settings);
  app.add_option("--role", role, "robot or controller")
      ->required()
      ->check(CLI::IsMember({"robot", "controller"}));
  app.add_option("--port", port, "the controller's port (controller: 0 = any)");
  std::string address = "127.0.0.1";
  app.add_option("--address", address, "the controller's IPv4 address")->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError &e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (::inet_pton(AF_INET, address.c_str(), &g_address) != 1) {
    std::cerr << kProgram << ": --address " << address << " is not an IPv4 address\n";
    return 2;
  }
  if (role == "controller")
    return controller(settings, port);
  if (port == 0) {
    std::cerr << kProgram << ": --role robot needs --port\n";
    return 2;
  }
  return robot(settings, port);
}
