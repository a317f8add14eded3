// Where a provides port's callback runs (component/ports.hpp, Delivery): a port that opts in
// (Delivery::Listener) takes DDS samples on the reader's listener, every one and in order; a
// port that did not, or a callback that could not run there without waiting (the component's
// property lock held elsewhere, another of its callbacks running), goes through the receive
// loop's thread, still every sample in order. Writer and reader share one participant: Cyclone
// calls the listener of a reader in the writer's process on a thread of its own or the writer's,
// never on the receive loop's, which tells the two ways apart.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>

#include "component/ports.hpp"
#include "component/receive_loop.hpp"
#include "dds/port_qos.hpp"
#include "test_domain.hpp"

using namespace std::chrono_literals;
using namespace rsca;
using component::Delivery;
using component::ProvidesPort;
using component::UsesPort;
using component::detail::ReceiveLoop;
using port::Samples;

namespace {

// What the callback saw: each sample's sequence and whether it ran on the loop's thread.
struct Seen {
  std::mutex mutex;
  std::condition_variable changed;
  std::vector<std::uint64_t> sequences;
  std::vector<bool> on_loop;

  // Waits (bounded, for a hung delivery to fail the test rather than stall it) until `count`
  // samples were seen.
  bool wait_for(std::size_t count) {
    std::unique_lock lock(mutex);
    return changed.wait_for(lock, 10s, [&] { return sequences.size() >= count; });
  }
  std::size_t count_on_loop(bool loop) {
    std::lock_guard lock(mutex);
    std::size_t n = 0;
    for (bool b : on_loop)
      n += b == loop ? 1 : 0;
    return n;
  }
  bool in_order() {
    std::lock_guard lock(mutex);
    for (std::size_t i = 0; i < sequences.size(); ++i)
      if (sequences[i] != i)
        return false;
    return true;
  }
};

// A component's receive side without the component: its property lock, a receive loop that
// polls one provides port, the port, and a uses port writing to it over DDS in this process.
class Pair {
public:
  explicit Pair(Delivery delivery, const std::string &topic)
      : participant_(test::participant()),
        in_(
            "in",
            [this](const Samples &s) {
              std::lock_guard lock(seen.mutex);
              seen.sequences.push_back(s.sequence);
              seen.on_loop.push_back(std::this_thread::get_id() == loop_thread_.load());
              seen.changed.notify_all();
            },
            delivery),
        out_("out") {
    auto loop = ReceiveLoop::start(
        [this] {
          in_.take_all(loop_->delivering());
          ++polls_;
          polls_.notify_all();
        },
        &owner_lock);
    REQUIRE(loop.has_value());
    loop_ = std::move(*loop);
    loop_thread_ = loop_->thread().get_id();
    auto qos = dds::qos_from_json({{"reliability", "reliable"}, {"history", "keepall"}});
    REQUIRE(qos.has_value());
    auto in = in_.connect(participant_->get(), loop_.get(), "c", topic, qos->get());
    INFO((in ? std::string() : in.error().to_string()));
    REQUIRE(in.has_value());
    auto out = out_.connect(participant_->get(), nullptr, "c", topic, qos->get());
    INFO((out ? std::string() : out.error().to_string()));
    REQUIRE(out.has_value());
    REQUIRE(matched());
    // The first poll (the wake of the reader's attachment) is over, and the loop has let go of
    // its delivery (run_here could run): from now on only a sample the listener hands over wakes
    // the loop.
    polls_.wait(0);
    loop_->set_delivering(true);
    REQUIRE(eventually([&] { return loop_->run_here([] {}); }));
  }
  ~Pair() {
    in_.disconnect_all();
    out_.disconnect_all();
    loop_->stop();
  }

  // As the component host does when its component stops: no callback after this returns.
  void stop_delivering() {
    loop_->set_delivering(false);
    in_.quiesce();
  }
  void start_delivering() { loop_->set_delivering(true); }
  // Waits (bounded) until the port has received `count` samples, delivered or not.
  bool received(std::uint64_t count) {
    return eventually([&] { return in_.status().at(0).samples >= count; });
  }

  void write(std::uint64_t sequence) {
    Samples s;
    s.sequence = sequence;
    s.samples = {static_cast<double>(sequence)};
    REQUIRE(out_.write(s).has_value());
  }

  std::recursive_mutex owner_lock; // the component's property lock
  Seen seen;

private:
  bool matched() {
    return eventually(
        [&] { return out_.matched("c").value_or(0) >= 1 && in_.matched("c").value_or(0) >= 1; });
  }
  // Bounded, for a hung connection to fail the test rather than stall it.
  static bool eventually(const std::function<bool()> &condition) {
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (!condition()) {
      if (std::chrono::steady_clock::now() > deadline)
        return false;
      std::this_thread::sleep_for(1ms); // pacing the poll of a condition
    }
    return true;
  }

  std::shared_ptr<dds::Participant> participant_;
  std::atomic<std::thread::id> loop_thread_{};
  std::atomic<int> polls_{0};
  ProvidesPort<Samples> in_;
  UsesPort<Samples> out_;
  std::unique_ptr<ReceiveLoop> loop_;
};

// Of this test process's own (DDS topic names take letters, digits and '_' only).
std::string topic(const char *name) {
  std::string tag = test::isolated_tag();
  std::replace(tag.begin(), tag.end(), '-', '_');
  return std::string(name) + "_" + tag;
}

// Holds a lock on a thread of its own until released, as a configure holds the property lock.
class HeldElsewhere {
public:
  explicit HeldElsewhere(std::recursive_mutex &m) {
    thread_ = std::thread([this, &m] {
      std::unique_lock held(m);
      std::unique_lock lock(mutex_);
      holding_ = true;
      changed_.notify_all();
      changed_.wait(lock, [this] { return released_; });
    });
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [this] { return holding_; });
  }
  ~HeldElsewhere() { release(); }
  void release() {
    {
      std::lock_guard lock(mutex_);
      released_ = true;
    }
    changed_.notify_all();
    if (thread_.joinable())
      thread_.join();
  }

private:
  std::mutex mutex_;
  std::condition_variable changed_;
  bool holding_ = false, released_ = false;
  std::thread thread_;
};

constexpr std::uint64_t kSamples = 200;

} // namespace

TEST_CASE("a port that opts in takes every DDS sample on the listener's thread in order",
          "[unit][port][listener-delivery]") {
  Pair pair(Delivery::Listener, topic("listener_in_order"));
  for (std::uint64_t i = 0; i < kSamples; ++i)
    pair.write(i);
  REQUIRE(pair.seen.wait_for(kSamples));
  CHECK(pair.seen.in_order());
  CHECK(pair.seen.count_on_loop(false) == kSamples);
}

TEST_CASE("a port that did not opt in takes every DDS sample on the receive loop in order",
          "[unit][port][listener-delivery]") {
  Pair pair(Delivery::ReceiveThread, topic("loop_in_order"));
  for (std::uint64_t i = 0; i < kSamples; ++i)
    pair.write(i);
  REQUIRE(pair.seen.wait_for(kSamples));
  CHECK(pair.seen.in_order());
  CHECK(pair.seen.count_on_loop(true) == kSamples);
}

TEST_CASE("a callback that would wait for the property lock goes through the receive loop",
          "[unit][port][listener-delivery]") {
  Pair pair(Delivery::Listener, topic("held_lock"));
  {
    HeldElsewhere configuring(pair.owner_lock);
    for (std::uint64_t i = 0; i < kSamples; ++i)
      pair.write(i);
    REQUIRE(pair.seen.wait_for(kSamples));
    CHECK(pair.seen.count_on_loop(true) == kSamples);
  }
  // Once the lock is free the listener delivers again: one sample at a time until one goes
  // there (the loop may still be finishing the poll the last hand-over rang for).
  std::uint64_t next = kSamples;
  while (pair.seen.count_on_loop(false) == 0 && next < 10 * kSamples) {
    pair.write(next);
    REQUIRE(pair.seen.wait_for(++next));
  }
  CHECK(pair.seen.count_on_loop(false) > 0);
  CHECK(pair.seen.in_order());
}

TEST_CASE("a port that opts in delivers nothing while its component is stopped",
          "[unit][port][listener-delivery]") {
  Pair pair(Delivery::Listener, topic("stopped"));
  pair.stop_delivering();
  pair.write(0); // taken by the loop and dropped, as without the listener
  REQUIRE(pair.received(1));
  pair.start_delivering();
  pair.write(0); // the first delivered (sequences count from 0 in Seen::in_order)
  REQUIRE(pair.seen.wait_for(1));
  CHECK(pair.seen.in_order());
  CHECK(pair.seen.sequences.size() == 1);
}
