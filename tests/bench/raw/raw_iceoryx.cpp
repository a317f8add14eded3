// The raw iceoryx baseline of the same-host port round trip (tools/bench port-latency): iceoryx
// 2.0.3 from Debian, as its users would write a ping-pong between two processes, each woken by a
// WaitSet; with --spin-us S, after data each looks for more for S microseconds (yielding the CPU)
// before it sleeps, as rsca's receive thread does after same-host data (RSCA_RECEIVE_SPIN_US).
// --instance lets two pairs share one RouDi (each its own services). `roudi` runs the daemon every
// iceoryx process needs (one per machine: shm/arena.hpp says why rsca does not build on it); `echo`
// writes back what it takes; `ping` measures round trips and writes them, in ns, to --output, with
// a JSON summary on stdout.
#include <sched.h>

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

iox::capro::ServiceDescription service(const std::string &instance, const char *event) {
  return {"rsca", iox::capro::IdString_t(iox::cxx::TruncateToCapacity, instance.c_str()),
          iox::capro::IdString_t(iox::cxx::TruncateToCapacity, event)};
}

// After data, how long a side looks for more before it sleeps (0: it sleeps at once).
std::chrono::microseconds spin_time{0};

bool take_and_release(iox::popo::UntypedSubscriber &subscriber) {
  auto taken = subscriber.take();
  if (taken.has_error())
    return false;
  subscriber.release(taken.value());
  return true;
}

// Looks for a sample for spin_time, yielding the CPU as rsca's receive loop does.
bool spin_for_one(iox::popo::UntypedSubscriber &subscriber) {
  const auto until = std::chrono::steady_clock::now() + spin_time;
  while (std::chrono::steady_clock::now() < until) {
    if (take_and_release(subscriber))
      return true;
    sched_yield();
  }
  return false;
}

// Waits until `subscriber` has a sample (spinning first when spin_time is set: each call follows
// data), then takes and releases it; false when stopping or nothing came within the timeout.
bool take_one(iox::popo::UntypedSubscriber &subscriber, iox::popo::WaitSet<> &waitset,
              std::chrono::milliseconds timeout) {
  if (spin_time.count() > 0 && spin_for_one(subscriber))
    return true;
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (!stopping && std::chrono::steady_clock::now() < until) {
    if (take_and_release(subscriber))
      return true;
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
bool init_runtime(const std::string &name) {
  iox::runtime::PoshRuntime::initRuntime(
      iox::RuntimeName_t(iox::cxx::TruncateToCapacity, name.c_str()));
  return true;
}

// One side of the ping-pong: this process's iceoryx runtime, what it sends on `out`, and what it
// waits for on `in`.
struct Side {
  Side(const std::string &role, const std::string &instance, const char *out, const char *in)
      : initialized(init_runtime("rsca-bench-iceoryx-" + role + "-" + instance)),
        publisher(service(instance, out)), subscriber(service(instance, in)) {
    attached = !waitset.attachState(subscriber, iox::popo::SubscriberState::HAS_DATA).has_error();
  }
  bool initialized;
  iox::popo::UntypedPublisher publisher;
  iox::popo::UntypedSubscriber subscriber;
  iox::popo::WaitSet<> waitset;
  bool attached = false;
};

int run_echo(std::size_t bytes, const std::string &instance) {
  Side side("echo", instance, "pong", "ping");
  if (!side.attached)
    return 1;
  std::puts("ready");
  std::fflush(stdout);
  while (!stopping)
    if (take_one(side.subscriber, side.waitset, std::chrono::milliseconds(200)))
      publish(side.publisher, bytes);
  return 0;
}

int run_ping(std::size_t bytes, int count, int warmup, const std::string &output,
             const std::string &instance) {
  Side side("ping", instance, "ping", "pong");
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
  std::string output, instance = "bench";
  std::uint64_t spin_us = 0;
  auto *roudi = app.add_subcommand("roudi", "Runs RouDi until SIGTERM");
  auto *echo = app.add_subcommand("echo", "Writes back every ping, until SIGTERM");
  echo->add_option("--bytes", bytes);
  echo->add_option("--instance", instance, "Service instance: pairs of one RouDi apart");
  echo->add_option("--spin-us", spin_us, "After data, look for more this long before sleeping")
      ->check(CLI::Range(0, 1'000'000));
  auto *ping = app.add_subcommand("ping", "Strict ping-pong; round-trip times to --output");
  ping->add_option("--bytes", bytes);
  ping->add_option("--count", count);
  ping->add_option("--warmup", warmup);
  ping->add_option("--output", output)->required();
  ping->add_option("--instance", instance);
  ping->add_option("--spin-us", spin_us)->check(CLI::Range(0, 1'000'000));
  CLI11_PARSE(app, argc, argv);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGINT, on_signal);
  if (roudi->parsed())
    return run_roudi();
  spin_time = std::chrono::microseconds(spin_us);
  if (echo->parsed())
    return run_echo(bytes, instance);
  return run_ping(bytes, count, warmup, output, instance);
}
