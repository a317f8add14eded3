// The raw iceoryx baseline of the same-host port round trip (tools/bench port-latency): iceoryx
// 2.0.3 from Debian, as its users would write a ping-pong between two processes, each woken by a
// WaitSet (no spinning). `roudi` runs the daemon every iceoryx process needs (one per machine:
// shm/arena.hpp says why rsca does not build on it); `echo` writes back what it takes; `ping`
// measures round trips and writes them, in ns, to --output, with a JSON summary on stdout.
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <sys/resource.h>

#include "iceoryx_posh/iceoryx_posh_config.hpp"
#include "iceoryx_posh/internal/roudi/roudi.hpp"
#include "iceoryx_posh/popo/untyped_publisher.hpp"
#include "iceoryx_posh/popo/untyped_subscriber.hpp"
#include "iceoryx_posh/popo/wait_set.hpp"
#include "iceoryx_posh/roudi/iceoryx_roudi_components.hpp"
#include "iceoryx_posh/runtime/posh_runtime.hpp"

namespace {

std::atomic<bool> stopping{false};

void on_signal(int) {
  stopping = true;
}

double cpu_us() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) * 1e6 +
         static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

int run_roudi() {
  iox::RouDiConfig_t config = iox::RouDiConfig_t().setDefaults();
  iox::roudi::IceOryxRouDiComponents components(config);
  iox::roudi::RouDi roudi(components.rouDiMemoryManager, components.portManager,
                          iox::roudi::RouDi::RoudiStartupParameters{});
  std::puts("ready");
  std::fflush(stdout);
  while (!stopping)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  return 0;
}

iox::capro::ServiceDescription service(const char *event) {
  return {"rsca", "bench", iox::capro::IdString_t(iox::cxx::TruncateToCapacity, event)};
}

// Waits (no spinning) until `subscriber` has a sample, then takes and releases it; false when
// stopping or nothing came within the timeout.
bool take_one(iox::popo::UntypedSubscriber &subscriber, iox::popo::WaitSet<> &waitset,
              std::chrono::milliseconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (!stopping && std::chrono::steady_clock::now() < until) {
    auto taken = subscriber.take();
    if (!taken.has_error()) {
      subscriber.release(taken.value());
      return true;
    }
    waitset.timedWait(iox::units::Duration::fromMilliseconds(100));
  }
  return false;
}

bool publish(iox::popo::UntypedPublisher &publisher, std::size_t bytes) {
  auto loaned = publisher.loan(static_cast<std::uint32_t>(bytes));
  if (loaned.has_error())
    return false;
  std::memset(loaned.value(), 0x5a, bytes);
  publisher.publish(loaned.value());
  return true;
}

// The process's iceoryx runtime, registered with RouDi: first, before any port.
bool init_runtime(const char *name) {
  iox::runtime::PoshRuntime::initRuntime(iox::RuntimeName_t(iox::cxx::TruncateToCapacity, name));
  return true;
}

// One side of the ping-pong: this process's iceoryx runtime, what it sends on `out`, and what it
// waits for on `in`.
struct Side {
  Side(const char *runtime, const char *out, const char *in)
      : initialized(init_runtime(runtime)), publisher(service(out)), subscriber(service(in)) {
    attached = !waitset.attachState(subscriber, iox::popo::SubscriberState::HAS_DATA).has_error();
  }
  bool initialized;
  iox::popo::UntypedPublisher publisher;
  iox::popo::UntypedSubscriber subscriber;
  iox::popo::WaitSet<> waitset;
  bool attached = false;
};

int run_echo(std::size_t bytes) {
  Side side("rsca-bench-iceoryx-echo", "pong", "ping");
  if (!side.attached)
    return 1;
  std::puts("ready");
  std::fflush(stdout);
  while (!stopping)
    if (take_one(side.subscriber, side.waitset, std::chrono::milliseconds(200)))
      publish(side.publisher, bytes);
  return 0;
}

int run_ping(std::size_t bytes, int count, int warmup, const std::string &output) {
  Side side("rsca-bench-iceoryx-ping", "ping", "pong");
  if (!side.attached)
    return 1;
  auto &publisher = side.publisher;
  auto &subscriber = side.subscriber;
  auto &waitset = side.waitset;
  // Until the echo answers: both have matched.
  while (!stopping) {
    publish(publisher, bytes);
    if (take_one(subscriber, waitset, std::chrono::milliseconds(100)))
      break;
  }
  const double cpu_before = cpu_us();
  std::vector<std::uint64_t> rtts;
  rtts.reserve(static_cast<std::size_t>(count));
  int completed = 0;
  for (int i = 0; i < warmup + count && !stopping; ++i) {
    const auto sent = std::chrono::steady_clock::now();
    if (!publish(publisher, bytes) || !take_one(subscriber, waitset, std::chrono::seconds(5)))
      return 2;
    const auto rtt = std::chrono::steady_clock::now() - sent;
    if (i < warmup)
      continue;
    rtts.push_back(static_cast<std::uint64_t>(
        std::chrono::duration_cast<std::chrono::nanoseconds>(rtt).count()));
    ++completed;
  }
  FILE *file = std::fopen(output.c_str(), "wb");
  if (file == nullptr)
    return 3;
  std::fwrite(rtts.data(), sizeof(std::uint64_t), rtts.size(), file);
  std::fclose(file);
  std::printf(
      "%s\n",
      nlohmann::json{{"completed", completed}, {"resent", 0}, {"cpu_us", cpu_us() - cpu_before}}
          .dump()
          .c_str());
  return 0;
}

} // namespace

int main(int argc, char **argv) {
  CLI::App app("Raw iceoryx ping-pong: the same-host baseline of tools/bench port-latency");
  app.require_subcommand(1);
  std::size_t bytes = 64;
  int count = 2000, warmup = 2000;
  std::string output;
  auto *roudi = app.add_subcommand("roudi", "Runs RouDi until SIGTERM");
  auto *echo = app.add_subcommand("echo", "Writes back every ping, until SIGTERM");
  echo->add_option("--bytes", bytes);
  auto *ping = app.add_subcommand("ping", "Strict ping-pong; round-trip times to --output");
  ping->add_option("--bytes", bytes);
  ping->add_option("--count", count);
  ping->add_option("--warmup", warmup);
  ping->add_option("--output", output)->required();
  CLI11_PARSE(app, argc, argv);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGINT, on_signal);
  if (roudi->parsed())
    return run_roudi();
  if (echo->parsed())
    return run_echo(bytes);
  return run_ping(bytes, count, warmup, output);
}
