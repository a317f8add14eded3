// The in-host port round trip (component/local_topics.hpp): a ping and an echo component's ports
// in one process, each provides port drained by its own receive thread as in a component host,
// connected in-host. 64-byte samples (8 doubles), round trips one at a time; prints JSON with
// the percentiles in microseconds. The control plane plays no part: this is the data path only.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <vector>

#include "component/ports.hpp"
#include "component/receive_loop.hpp"
#include "dds/port_qos.hpp"

using namespace rsca;
using component::ProvidesPort;
using component::UsesPort;
using component::detail::ReceiveLoop;
using port::Samples;

namespace {

std::unique_ptr<ReceiveLoop> loop_polling(component::PortBase &port) {
  auto loop = ReceiveLoop::start([&port] { port.take_all(true); });
  if (!loop) {
    std::fprintf(stderr, "%s\n", loop.error().to_string().c_str());
    std::exit(1);
  }
  return std::move(*loop);
}

void connect(component::PortBase &port, ReceiveLoop *loop, const char *topic,
             const dds_qos_t *qos) {
  if (auto ok = port.connect(0, loop, topic, topic, qos, std::nullopt, /*local=*/true); !ok) {
    std::fprintf(stderr, "%s\n", ok.error().to_string().c_str());
    std::exit(1);
  }
}

double percentile(std::vector<double> values, double p) {
  std::sort(values.begin(), values.end());
  return values[static_cast<std::size_t>(p / 100.0 * static_cast<double>(values.size() - 1))];
}

} // namespace

int main(int argc, char **argv) {
  const int rounds = argc > 1 ? std::atoi(argv[1]) : 20000;
  auto qos =
      dds::qos_from_json({{"reliability", "reliable"}, {"history", "keeplast"}, {"depth", 16}});
  if (!qos) {
    std::fprintf(stderr, "bad QoS\n");
    return 1;
  }
  // Strict ping-pong, as the port-latency benchmark's ping component does it: the next ping is
  // written from the callback that received the echo of the last (no hand-off to another thread).
  const int total = rounds + 1000; // the first 1000 warm up
  std::vector<double> micros;
  micros.reserve(static_cast<std::size_t>(rounds));
  std::atomic<bool> done{false};
  Samples sample;
  sample.samples.assign(8, 1.0); // 64 bytes of payload
  auto began = std::chrono::steady_clock::now();
  UsesPort<Samples> ping_out("out");
  ProvidesPort<Samples> ping_in("in", [&](const Samples &s) {
    const auto now = std::chrono::steady_clock::now();
    if (static_cast<int>(s.sequence) >= 1000)
      micros.push_back(std::chrono::duration<double, std::micro>(now - began).count());
    if (static_cast<int>(s.sequence) + 1 == total) {
      done.store(true);
      done.notify_one();
      return;
    }
    sample.sequence = s.sequence + 1;
    began = std::chrono::steady_clock::now();
    ping_out.write(sample);
  });
  UsesPort<Samples> echo_out("out");
  ProvidesPort<Samples> echo_in("in", [&](const Samples &s) { echo_out.write(s); });
  auto ping_loop = loop_polling(ping_in);
  auto echo_loop = loop_polling(echo_in);
  connect(echo_in, echo_loop.get(), "in_host_bench_ping", qos->get());
  connect(ping_out, nullptr, "in_host_bench_ping", qos->get());
  connect(ping_in, ping_loop.get(), "in_host_bench_echo", qos->get());
  connect(echo_out, nullptr, "in_host_bench_echo", qos->get());

  began = std::chrono::steady_clock::now();
  ping_out.write(sample);
  done.wait(false);
  std::printf("{\"rounds\": %d, \"p50_us\": %.2f, \"p90_us\": %.2f, \"p99_us\": %.2f}\n", rounds,
              percentile(micros, 50), percentile(micros, 90), percentile(micros, 99));
  // The ports go before their loops: a connection leaves its topic first.
  ping_in.disconnect_all();
  echo_in.disconnect_all();
  return 0;
}
