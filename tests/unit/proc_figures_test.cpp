// A process's figures from /proc (process/proc_figures.hpp): the stat line on canned text, CPU %
// from two readings, and the sampler on this very process.
#include <chrono>
#include <ctime>

#include <unistd.h>

#include <catch2/catch.hpp>

#include "process/proc_figures.hpp"

using namespace std::chrono_literals;
using rsca::process::cpu_percent;
using rsca::process::CpuSampler;
using rsca::process::parse_stat_line;

namespace {

// A real line's shape (proc(5)): utime 1200, stime 300, num_threads 7, starttime 98765, rss 2048.
constexpr const char *kLine =
    "4242 (a (b) c) S 1 4242 4242 0 -1 4194560 1000 0 0 0 1200 300 0 0 20 0 7 0 98765 123456789 "
    "2048 18446744073709551615 1 1 0 0 0 0 0 0 0 0 0 0 17 1 0 0 0 0 0\n";

} // namespace

TEST_CASE("a stat line is read after the command's last parenthesis, whatever the command holds",
          "[proc]") {
  auto stat = parse_stat_line(kLine);
  REQUIRE(stat.has_value());
  CHECK(stat->cpu_ticks == 1500);
  CHECK(stat->threads == 7);
  CHECK(stat->start_ticks == 98765);
  CHECK(stat->rss_pages == 2048);
}

TEST_CASE("a command that looks like more fields does not shift them", "[proc]") {
  auto stat = parse_stat_line(
      "7 (x) S 1 2 3 4 5 6 7 8 9 10 11 12 13 14) S 1 7 7 0 -1 0 0 0 0 0 5 6 0 0 20 0 3 0 42 1 9 "
      "0\n");
  REQUIRE(stat.has_value());
  CHECK(stat->cpu_ticks == 11);
  CHECK(stat->threads == 3);
  CHECK(stat->start_ticks == 42);
  CHECK(stat->rss_pages == 9);
}

TEST_CASE("a stat line without its fields is refused", "[proc]") {
  CHECK_FALSE(parse_stat_line("").has_value());
  CHECK_FALSE(parse_stat_line("12 (no close S 1 2 3").has_value());
  CHECK_FALSE(parse_stat_line("12 (short) S 1 2 3").has_value());
  CHECK_FALSE(
      parse_stat_line("12 (bad) S 1 1 1 0 -1 0 0 0 0 0 x 1 0 0 20 0 1 0 1 1 1").has_value());
  CHECK_FALSE(parse_stat_line(") 12 (reversed S 1 2").has_value());
}

TEST_CASE("CPU percent is CPU time over elapsed time, of one CPU", "[proc]") {
  CHECK(cpu_percent(100, 150, 1s, 100) == Approx(50.0));
  CHECK(cpu_percent(0, 400, 2s, 100) == Approx(200.0)); // busy on two CPUs
  CHECK(cpu_percent(10, 10, 500ms, 100) == Approx(0.0));
  CHECK(cpu_percent(10, 20, 0s, 100) == 0.0); // no time: nothing to say
  CHECK(cpu_percent(20, 10, 1s, 100) == 0.0); // a counter that went back: another process
  CHECK(cpu_percent(0, 250, 1s, 250) == Approx(100.0));
}

TEST_CASE("the sampler reads this process and sees it burn CPU between two readings", "[proc]") {
  CpuSampler sampler;
  auto first = sampler.read(::getpid());
  REQUIRE(first.has_value());
  CHECK(first->rss_bytes > 0);
  CHECK(first->threads >= 1);
  CHECK(first->cpu_percent >= 0);
  // Busy for longer than the sampler's shortest interval, so the next reading is a fresh one, and
  // for 300 ms of CPU time whatever else the machine runs: this thread's own CPU % is then known.
  const auto wall_start = std::chrono::steady_clock::now();
  const auto cpu_start = std::clock();
  volatile std::uint64_t spin = 0;
  while (std::clock() - cpu_start < CLOCKS_PER_SEC * 3 / 10 ||
         std::chrono::steady_clock::now() - wall_start < CpuSampler::kMinInterval + 50ms)
    spin = spin + 1;
  auto second = sampler.read(::getpid());
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  const double own = 100.0 * static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC / wall;
  REQUIRE(second.has_value());
  // Within the ticks' resolution (10 ms a tick on the readings' edges) of what this thread used.
  CHECK(second->cpu_percent > own * 0.6);
  CHECK_FALSE(sampler.read(0x7ffffff0).has_value()); // no such process
}
