// rsca-bench-raw: the raw Cyclone DDS baseline of the port benchmarks (tests/bench/port_bench.py):
// the same exchanges as the benchmark components, written directly on the Cyclone C API, with the
// same IDL types (dds/ports.idl), the same QoS (the JSON of component.connect, turned into a DDS
// QoS by the same dds::qos_from_json) and the same Cyclone configuration (a participant made by
// dds::Participant from the RSCA_DDS_* environment with the settings of a component process). No
// component runtime, no control endpoint, no domain: one participant, the data readers and writers,
// a waitset with a read condition (or, with --wake listener, the wake rsca's receive loop uses),
// and dds_take with loans. With --spin-us S the receiving thread, after data, looks for more for S
// microseconds (yielding the CPU) before it sleeps, as rsca's receive thread does after same-host
// data (RSCA_RECEIVE_SPIN_US): the busy-polling side of a like-for-like comparison.
//
//   rsca-bench-raw sizes
//   rsca-bench-raw ping --out TOPIC --in TOPIC --qos JSON [--wake waitset|listener] [--spin-us S]
//                       --count N --warmup W --output FILE
//   rsca-bench-raw echo --in TOPIC --out TOPIC --qos JSON [--wake waitset|listener] [--spin-us S]
//                       (until SIGTERM)
//   rsca-bench-raw pub --topic TOPIC --qos JSON --subscribers N --output FILE [schedule...]
//   rsca-bench-raw sub --topic TOPIC --qos JSON --capacity N --output FILE   (until SIGTERM)
//   rsca-bench-raw discovery --participants N --timeout-ms T [--existing K]
//
// Times, payloads and result files: tests/bench/bench_common.hpp.
#include <fcntl.h>
#include <linux/futex.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <dds/ddsi/ddsi_serdata.h>
#include <nlohmann/json.hpp>

#include "../bench_common.hpp"
#include "dds/participant.hpp"
#include "dds/port_qos.hpp"
#include "ports.h" // generated from dds/ports.idl
#include "raw_discovery.hpp"

namespace {

using rsca::bench::mono_ns;

std::atomic<bool> g_stop{false};

void on_signal(int) {
  g_stop = true;
}

[[noreturn]] void die(const std::string &what) {
  std::fprintf(stderr, "rsca-bench-raw: %s\n", what.c_str());
  std::exit(1);
}

dds_entity_t must(dds_entity_t result, const char *what) {
  if (result < 0)
    die(std::string(what) + ": " + dds_strretcode(result));
  return result;
}

// The process's DDS side: a participant joined as a component process joins (the component lease
// and heartbeat), topics of the port types.
struct Dds {
  std::shared_ptr<rsca::dds::Participant> participant;
  rsca::dds::Qos qos;

  explicit Dds(const std::string &qos_json) {
    auto p =
        rsca::dds::Participant::create(rsca::dds::DdsSettings::from_environment().for_component());
    if (!p)
      die(p.error().to_string());
    participant = *p;
    auto json = nlohmann::json::parse(qos_json.empty() ? "{}" : qos_json, nullptr, false);
    if (json.is_discarded())
      die("--qos is not JSON: " + qos_json);
    auto q = rsca::dds::qos_from_json(json);
    if (!q)
      die(q.error().to_string());
    qos = std::move(*q);
  }

  dds_entity_t topic(const dds_topic_descriptor_t *descriptor, const std::string &name) const {
    return must(dds_create_topic(participant->get(), descriptor, name.c_str(), nullptr, nullptr),
                "creating a topic");
  }
  dds_entity_t writer(dds_entity_t topic) const {
    return must(dds_create_writer(participant->get(), topic, qos.get(), nullptr),
                "creating a writer");
  }
  dds_entity_t reader(dds_entity_t topic) const {
    return must(dds_create_reader(participant->get(), topic, qos.get(), nullptr),
                "creating a reader");
  }
};

// How the receiving thread learns that `reader` has data: a waitset with a read condition (the
// usual way), or a data-available listener that only wakes it with a flag and a futex, the way
// rsca's receive loop does (component/receive_loop.cpp). Either wakes every `timeout` as well,
// to look at the stop flag. With a spin time, after a take that had data the thread first looks
// for more that long, yielding the CPU, as rsca's receive loop does after same-host data.
enum class Wake { waitset, listener };

class Receiver {
public:
  Receiver(const Dds &dds, dds_entity_t reader, Wake wake, std::uint64_t spin_us = 0)
      : reader_(reader), spin_ns_(spin_us * 1000u) {
    if (wake == Wake::listener) {
      listener_ = dds_create_listener(this);
      dds_lset_data_available(listener_, &Receiver::on_data_available);
      must(dds_set_listener(reader_, listener_), "setting the data-available listener");
      return;
    }
    waitset_ = must(dds_create_waitset(dds.participant->get()), "creating a waitset");
    const dds_entity_t condition =
        must(dds_create_readcondition(reader_, DDS_ANY_STATE), "creating a read condition");
    must(dds_waitset_attach(waitset_, condition, reader_), "attaching the read condition");
  }
  ~Receiver() {
    if (listener_ == nullptr)
      return;
    dds_set_listener(reader_, nullptr);
    dds_delete_listener(listener_);
  }
  Receiver(const Receiver &) = delete;
  Receiver &operator=(const Receiver &) = delete;

  dds_entity_t reader() const { return reader_; }

  // What the last take found: data starts a spin before the next sleep.
  void took(dds_return_t n) { spin_next_ = spin_ns_ > 0 && n > 0; }

  void wait(dds_duration_t timeout) {
    if (spin_next_ && spin_for_data())
      return;
    if (listener_ == nullptr) {
      dds_waitset_wait(waitset_, nullptr, 0, timeout);
      return;
    }
    if (woken_.exchange(0) != 0)
      return;
    sleeping_.store(1);
    if (woken_.load() == 0) {
      const timespec until{static_cast<time_t>(timeout / DDS_NSECS_IN_SEC),
                           static_cast<long>(timeout % DDS_NSECS_IN_SEC)};
      ::syscall(SYS_futex, &woken_, FUTEX_WAIT_PRIVATE, 0, &until, nullptr, 0);
    }
    sleeping_.store(0);
    woken_.store(0);
  }

private:
  // Looks for data for the spin time; whatever else is runnable on this CPU (Cyclone's receive
  // thread, the other end of the exchange) goes first, as in rsca's ReceiveLoop::spin_for_wake.
  bool spin_for_data() {
    const std::uint64_t until = mono_ns() + spin_ns_;
    while (mono_ns() < until) {
      if (listener_ != nullptr ? woken_.exchange(0) != 0
                               : dds_waitset_wait(waitset_, nullptr, 0, 0) > 0)
        return true;
      sched_yield();
    }
    return false;
  }

  static void on_data_available(dds_entity_t, void *self) {
    auto *receiver = static_cast<Receiver *>(self);
    receiver->woken_.store(1);
    if (receiver->sleeping_.load() != 0)
      ::syscall(SYS_futex, &receiver->woken_, FUTEX_WAKE_PRIVATE, 1, nullptr, nullptr, 0);
  }

  dds_entity_t reader_;
  dds_entity_t waitset_ = 0;
  dds_listener_t *listener_ = nullptr;
  std::atomic<std::uint32_t> woken_{0};
  std::atomic<std::uint32_t> sleeping_{0};
  std::uint64_t spin_ns_;
  bool spin_next_ = false;
};

constexpr std::uint32_t kBatch = 32;

// CPU time of the whole process so far (all its threads, Cyclone's included), in microseconds.
std::uint64_t process_cpu_us() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  auto us = [](const timeval &t) {
    return static_cast<std::uint64_t>(t.tv_sec) * 1'000'000u +
           static_cast<std::uint64_t>(t.tv_usec);
  };
  return us(usage.ru_utime) + us(usage.ru_stime);
}

void write_results(const std::string &path, const std::vector<std::uint64_t> &values) {
  if (!rsca::bench::write_u64_file(path, values))
    die("cannot write " + path);
}

// ---- ping-pong ---------------------------------------------------------------------------------

// Sleeps until the monotonic time `at_ns` (ns); at once if it has passed.
void pause_until(std::uint64_t at_ns) {
  const std::uint64_t now = mono_ns();
  if (at_ns <= now)
    return;
  const std::uint64_t ns = at_ns - now;
  const timespec pause{static_cast<time_t>(ns / 1'000'000'000u),
                       static_cast<long>(ns % 1'000'000'000u)};
  nanosleep(&pause, nullptr);
}

int ping(const std::string &out_topic, const std::string &in_topic, const std::string &qos,
         Wake wake, std::uint64_t spin_us, std::uint64_t count, std::uint64_t warmup,
         std::uint64_t timeout_ms, std::uint64_t interval_us, const std::string &output) {
  Dds dds(qos);
  const dds_entity_t writer = dds.writer(dds.topic(&rsca_port_SampleSeq_desc, out_topic));
  Receiver in(dds, dds.reader(dds.topic(&rsca_port_SampleSeq_desc, in_topic)), wake, spin_us);
  double values[rsca::bench::kSampleDoubles] = {0, 0, 0};
  rsca_port_SampleSeq sample{};
  sample.stream_id = const_cast<char *>("");
  sample.samples._buffer = values;
  sample.samples._length = sample.samples._maximum = rsca::bench::kSampleDoubles;
  std::vector<std::uint64_t> rtts;
  rtts.reserve(count);
  const std::uint64_t target = warmup + count, timeout_ns = timeout_ms * 1'000'000u;
  std::uint64_t completed = 0, resent = 0, sent_at = 0;
  auto send = [&](std::uint64_t now) {
    sent_at = now;
    sample.timestamp_ns = now;
    if (dds_return_t rc = dds_write(writer, &sample); rc < 0)
      std::fprintf(stderr, "rsca-bench-raw ping: write failed: %s\n", dds_strretcode(rc));
  };
  const std::uint64_t cpu_before = process_cpu_us();
  send(mono_ns());
  while (completed < target && !g_stop) {
    in.wait(DDS_MSECS(10));
    void *samples[kBatch] = {nullptr};
    dds_sample_info_t infos[kBatch];
    const dds_return_t n = dds_take(in.reader(), samples, infos, kBatch, kBatch);
    in.took(n);
    bool answered = false;
    std::uint64_t now = 0;
    for (dds_return_t i = 0; i < n; ++i) {
      const auto *echo = static_cast<const rsca_port_SampleSeq *>(samples[i]);
      if (!infos[i].valid_data || answered || echo->sequence != sample.sequence ||
          echo->timestamp_ns != sample.timestamp_ns)
        continue; // a late echo of a ping that was sent again
      now = mono_ns();
      answered = true;
    }
    if (n > 0)
      dds_return_loan(in.reader(), samples, n);
    if (answered) {
      if (++completed > warmup)
        rtts.push_back(now - sent_at);
      if (completed < target) {
        ++sample.sequence;
        pause_until(sent_at + interval_us * 1000u);
        send(mono_ns());
      }
    } else if (mono_ns() - sent_at > timeout_ns) {
      ++resent;
      send(mono_ns());
    }
  }
  const std::uint64_t cpu_us = process_cpu_us() - cpu_before;
  write_results(output, rtts);
  std::printf("{\"completed\": %llu, \"resent\": %llu, \"cpu_us\": %llu}\n",
              static_cast<unsigned long long>(completed), static_cast<unsigned long long>(resent),
              static_cast<unsigned long long>(cpu_us));
  return completed >= target ? 0 : 1;
}

int echo(const std::string &in_topic, const std::string &out_topic, const std::string &qos,
         Wake wake, std::uint64_t spin_us) {
  Dds dds(qos);
  const dds_entity_t writer = dds.writer(dds.topic(&rsca_port_SampleSeq_desc, out_topic));
  Receiver in(dds, dds.reader(dds.topic(&rsca_port_SampleSeq_desc, in_topic)), wake, spin_us);
  std::uint64_t echoed = 0;
  while (!g_stop) {
    in.wait(DDS_MSECS(100));
    void *samples[kBatch] = {nullptr};
    dds_sample_info_t infos[kBatch];
    const dds_return_t n = dds_take(in.reader(), samples, infos, kBatch, kBatch);
    in.took(n);
    for (dds_return_t i = 0; i < n; ++i)
      if (infos[i].valid_data && dds_write(writer, samples[i]) >= 0)
        ++echoed;
    if (n > 0)
      dds_return_loan(in.reader(), samples, n);
  }
  std::printf("{\"echoed\": %llu}\n", static_cast<unsigned long long>(echoed));
  return 0;
}

// ---- fan-out -----------------------------------------------------------------------------------

struct Schedule {
  std::uint64_t warmup = 100;
  std::uint64_t latency_count = 1000;
  double latency_rate_hz = 100;
  std::vector<double> step_rates_hz;
  std::uint64_t step_ms = 1000;
  std::uint64_t gap_ms = 300;
};

int pub(const std::string &topic, const std::string &qos, std::int32_t subscribers,
        std::uint64_t match_timeout_ms, const Schedule &schedule, const std::string &output) {
  Dds dds(qos);
  const dds_entity_t writer = dds.writer(dds.topic(&rsca_port_PropertyEvent_desc, topic));
  const std::uint64_t started = mono_ns();
  dds_publication_matched_status_t matched{};
  for (;;) {
    dds_get_publication_matched_status(writer, &matched);
    if (static_cast<std::int32_t>(matched.current_count) >= subscribers || g_stop)
      break;
    if (mono_ns() - started > match_timeout_ms * 1'000'000u) {
      std::fprintf(stderr, "rsca-bench-raw pub: only %u of %d subscribers matched\n",
                   matched.current_count, subscribers);
      break;
    }
    dds_sleepfor(DDS_MSECS(5));
  }
  std::vector<rsca::bench::Phase> phases{{schedule.warmup, schedule.latency_rate_hz, 0},
                                         {schedule.latency_count, schedule.latency_rate_hz, 0}};
  for (double rate : schedule.step_rates_hz)
    phases.push_back(
        {static_cast<std::uint64_t>(rate * static_cast<double>(schedule.step_ms) / 1000.0 + 0.5),
         rate, schedule.gap_ms});
  rsca::bench::Pacer pacer(std::move(phases));
  std::vector<std::uint64_t> send_ns(pacer.total(), 0);
  std::string value;
  rsca_port_PropertyEvent event{};
  event.source = const_cast<char *>("");
  event.id = const_cast<char *>(rsca::bench::kEventId.data());
  std::uint64_t sequence = 0, sent = 0, failed = 0;
  while (!pacer.finished() && !g_stop) {
    const auto due = pacer.due(mono_ns());
    for (std::uint64_t i = 0; i < due.send; ++i, ++sequence) {
      rsca::bench::format_event_value(sequence, value);
      event.value = value.data();
      const std::uint64_t now = mono_ns();
      event.timestamp_ns = now;
      if (dds_write(writer, &event) >= 0) {
        send_ns[sequence] = now;
        ++sent;
      } else {
        ++failed;
      }
    }
    pacer.sent(due.send);
    if (!pacer.finished() && due.sleep_ns > 0) {
      const timespec pause{static_cast<time_t>(due.sleep_ns / 1'000'000'000u),
                           static_cast<long>(due.sleep_ns % 1'000'000'000u)};
      nanosleep(&pause, nullptr);
    }
  }
  write_results(output, send_ns);
  std::printf("{\"matched\": %u, \"sent\": %llu, \"failed_writes\": %llu, \"skipped\": %llu}\n",
              matched.current_count, static_cast<unsigned long long>(sent),
              static_cast<unsigned long long>(failed),
              static_cast<unsigned long long>(pacer.skipped()));
  return 0;
}

int sub(const std::string &topic, const std::string &qos, std::uint64_t capacity,
        const std::string &output) {
  Dds dds(qos);
  Receiver in(dds, dds.reader(dds.topic(&rsca_port_PropertyEvent_desc, topic)), Wake::waitset);
  std::vector<std::uint64_t> received_at(capacity, 0);
  std::uint64_t received = 0, unexpected = 0;
  while (!g_stop) {
    in.wait(DDS_MSECS(100));
    void *samples[kBatch] = {nullptr};
    dds_sample_info_t infos[kBatch];
    const dds_return_t n = dds_take(in.reader(), samples, infos, kBatch, kBatch);
    for (dds_return_t i = 0; i < n; ++i) {
      if (!infos[i].valid_data)
        continue;
      const std::uint64_t now = mono_ns();
      const auto *event = static_cast<const rsca_port_PropertyEvent *>(samples[i]);
      std::uint64_t sequence = 0;
      if (event->value == nullptr || !rsca::bench::parse_event_sequence(event->value, sequence) ||
          sequence >= capacity || received_at[sequence] != 0) {
        ++unexpected;
        continue;
      }
      received_at[sequence] = now;
      ++received;
    }
    if (n > 0)
      dds_return_loan(in.reader(), samples, n);
  }
  write_results(output, received_at);
  std::printf("{\"received\": %llu, \"unexpected\": %llu}\n",
              static_cast<unsigned long long>(received),
              static_cast<unsigned long long>(unexpected));
  return 0;
}

// ---- sizes -------------------------------------------------------------------------------------

// What Cyclone serializes for a sample of `topic`'s type, without the 4-byte encapsulation header:
// written to a reader of this participant, taken back serialized (dds_takecdr).
std::uint32_t serialized_size(const Dds &dds, dds_entity_t topic, const void *sample) {
  const dds_entity_t reader = dds.reader(topic);
  const dds_entity_t writer = dds.writer(topic);
  must(dds_write(writer, sample), "writing a sample");
  struct ddsi_serdata *data = nullptr;
  dds_sample_info_t info;
  for (int tries = 0; tries < 1000; ++tries) {
    if (dds_takecdr(reader, &data, 1, &info, DDS_ANY_STATE) == 1)
      break;
    dds_sleepfor(DDS_MSECS(1));
  }
  if (data == nullptr)
    die("the sample written did not come back");
  const std::uint32_t size = ddsi_serdata_size(data);
  ddsi_serdata_unref(data);
  dds_delete(writer);
  dds_delete(reader);
  return size - 4;
}

int sizes() {
  Dds dds("{}");
  double values[rsca::bench::kSampleDoubles] = {0, 0, 0};
  rsca_port_SampleSeq sample{};
  sample.stream_id = const_cast<char *>("");
  sample.samples._buffer = values;
  sample.samples._length = sample.samples._maximum = rsca::bench::kSampleDoubles;
  std::string value;
  rsca::bench::format_event_value(1234567, value);
  rsca_port_PropertyEvent event{};
  event.source = const_cast<char *>("");
  event.id = const_cast<char *>(rsca::bench::kEventId.data());
  event.value = value.data();
  std::printf("{\"ping_sample_bytes\": %u, \"event_bytes\": %u}\n",
              serialized_size(dds, dds.topic(&rsca_port_SampleSeq_desc, "rsca_bench_sizes_samples"),
                              &sample),
              serialized_size(dds,
                              dds.topic(&rsca_port_PropertyEvent_desc, "rsca_bench_sizes_events"),
                              &event));
  return 0;
}

} // namespace

int main(int argc, char **argv) {
  CLI::App app{"rsca-bench-raw — the raw Cyclone DDS baseline of tests/bench/port_bench.py"};
  app.require_subcommand(1);
  std::string out_topic, in_topic, topic, qos, output;
  std::uint64_t count = 10000, warmup = 100, timeout_ms = 200, capacity = 0,
                match_timeout_ms = 30000;
  std::int32_t subscribers = 1;
  Schedule schedule;

  auto *ping_cmd = app.add_subcommand("ping", "Strict ping-pong; round-trip times to --output");
  ping_cmd->add_option("--out", out_topic, "Topic the pings go to")->required();
  ping_cmd->add_option("--in", in_topic, "Topic the echoes come back on")->required();
  ping_cmd->add_option("--qos", qos, "The connection QoS as JSON");
  ping_cmd->add_option("--count", count, "Round trips measured");
  ping_cmd->add_option("--warmup", warmup, "Round trips first, not measured");
  ping_cmd->add_option("--timeout-ms", timeout_ms, "Send a ping again after");
  std::uint64_t interval_us = 0;
  ping_cmd->add_option("--interval-us", interval_us,
                       "Pings start at most this often (0: each at once after the last echo), "
                       "as a periodic sensor's readings do");
  ping_cmd->add_option("--output", output, "File of the round-trip times")->required();
  const std::map<std::string, Wake> wakes{{"waitset", Wake::waitset}, {"listener", Wake::listener}};
  Wake wake = Wake::waitset;
  ping_cmd->add_option("--wake", wake, "How the receiving thread is woken")
      ->transform(CLI::CheckedTransformer(wakes));
  std::uint64_t spin_us = 0;
  ping_cmd->add_option("--spin-us", spin_us, "After data, look for more this long before sleeping")
      ->check(CLI::Range(0, 1'000'000));

  auto *echo_cmd = app.add_subcommand("echo", "Writes back every sample, until SIGTERM");
  echo_cmd->add_option("--in", in_topic)->required();
  echo_cmd->add_option("--out", out_topic)->required();
  echo_cmd->add_option("--qos", qos);
  echo_cmd->add_option("--wake", wake)->transform(CLI::CheckedTransformer(wakes));
  echo_cmd->add_option("--spin-us", spin_us)->check(CLI::Range(0, 1'000'000));

  auto *pub_cmd = app.add_subcommand("pub", "Publishes the fan-out schedule; send times");
  pub_cmd->add_option("--topic", topic)->required();
  pub_cmd->add_option("--qos", qos);
  pub_cmd->add_option("--subscribers", subscribers, "Readers to wait for");
  pub_cmd->add_option("--match-timeout-ms", match_timeout_ms);
  pub_cmd->add_option("--warmup", schedule.warmup);
  pub_cmd->add_option("--latency-count", schedule.latency_count);
  pub_cmd->add_option("--latency-rate-hz", schedule.latency_rate_hz);
  pub_cmd->add_option("--step-rates-hz", schedule.step_rates_hz)->delimiter(',');
  pub_cmd->add_option("--step-ms", schedule.step_ms);
  pub_cmd->add_option("--gap-ms", schedule.gap_ms);
  pub_cmd->add_option("--output", output)->required();

  auto *sub_cmd = app.add_subcommand("sub", "Receive times per sequence number, until SIGTERM");
  sub_cmd->add_option("--topic", topic)->required();
  sub_cmd->add_option("--qos", qos);
  sub_cmd->add_option("--capacity", capacity, "Sequence numbers recorded")->required();
  sub_cmd->add_option("--output", output)->required();

  auto *sizes_cmd = app.add_subcommand("sizes", "Serialized sizes of the benchmark payloads");

  std::size_t participants = 10;
  std::uint64_t discovery_timeout_ms = 30000;
  auto *discovery_cmd = app.add_subcommand(
      "discovery", "N participant processes at once; when each has discovered all the others");
  discovery_cmd->add_option("--participants", participants)->check(CLI::Range(1, 1000));
  discovery_cmd->add_option("--timeout-ms", discovery_timeout_ms, "Stop waiting after");
  std::size_t existing = 0;
  discovery_cmd->add_option("--existing", existing,
                            "Participants already running (a domain's daemons) to discover too: "
                            "with --participants 1, the join of one new participant");
  CLI11_PARSE(app, argc, argv);

  struct sigaction action {};
  action.sa_handler = on_signal;
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGINT, &action, nullptr);

  if (*ping_cmd)
    return ping(out_topic, in_topic, qos, wake, spin_us, count, warmup, timeout_ms, interval_us,
                output);
  if (*echo_cmd)
    return echo(in_topic, out_topic, qos, wake, spin_us);
  if (*pub_cmd)
    return pub(topic, qos, subscribers, match_timeout_ms, schedule, output);
  if (*sub_cmd)
    return sub(topic, qos, capacity, output);
  if (*sizes_cmd)
    return sizes();
  if (*discovery_cmd)
    return rsca::bench::raw::discovery(participants, existing, discovery_timeout_ms, g_stop);
  return 2;
}
