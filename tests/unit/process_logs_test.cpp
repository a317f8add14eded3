// node.logs on a log folder (node/process_logs.hpp): which file a request reads, the tail from a
// whole line, reading on from an offset, names that are no names, and text made valid UTF-8.
#include <filesystem>
#include <fstream>
#include <random>

#include <fmt/format.h>
#include <unistd.h>

#include <catch2/catch.hpp>

#include "node/process_logs.hpp"

namespace fs = std::filesystem;
namespace op = rsca::protocol::node;
using rsca::node::read_log;
using rsca::node::rotate_if_over;
using rsca::node::utf8_or_replaced;

namespace {

struct LogFolder {
  fs::path dir = fs::temp_directory_path() /
                 fmt::format("rsca-logs-test-{}-{}", getpid(), std::random_device{}());
  LogFolder() { fs::create_directories(dir / "App"); }
  ~LogFolder() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
  void write(const std::string &name, const std::string &text) const {
    std::ofstream(dir / "App" / name, std::ios::binary) << text;
  }
  void append(const std::string &name, const std::string &text) const {
    std::ofstream(dir / "App" / name, std::ios::binary | std::ios::app) << text;
  }
};

op::LogsRequest request(std::string component) {
  return {"App", std::move(component), std::nullopt, std::nullopt, std::nullopt};
}

} // namespace

TEST_CASE("a log is read by application and component, and read on from where it ended", "[logs]") {
  LogFolder logs;
  logs.write("Comp_1.log", "one\ntwo\n");
  auto first = read_log(logs.dir, request("Comp_1"), {});
  REQUIRE(first.has_value());
  CHECK(first->log == "App/Comp_1.log");
  CHECK(first->text == "one\ntwo\n");
  CHECK(first->next == 8);
  logs.write("Comp_1.log", "one\ntwo\nthree\npartial");
  auto r = request("Comp_1");
  r.offset = first->next;
  auto second = read_log(logs.dir, r, {});
  REQUIRE(second.has_value());
  CHECK(second->text == "three\n"); // the line being written waits for its end
  CHECK(second->next == 14);
}

TEST_CASE("a tail starts at a whole line", "[logs]") {
  LogFolder logs;
  logs.write("Comp_1.log", "0123456789\nabc\ndef\n");
  auto r = request("Comp_1");
  r.max_bytes = 10;
  auto tail = read_log(logs.dir, r, {});
  REQUIRE(tail.has_value());
  CHECK(tail->text == "abc\ndef\n");
  CHECK(tail->offset == 11);
}

TEST_CASE(
    "a log read from past its end with no older file (truncated since) is read from its start",
    "[logs]") {
  LogFolder logs;
  logs.write("Comp_1.log", "new\n");
  auto r = request("Comp_1");
  r.offset = 1000;
  auto read = read_log(logs.dir, r, {});
  REQUIRE(read.has_value());
  CHECK(read->text == "new\n");
  CHECK(read->offset == 0);
}

TEST_CASE("a hosted component's log is its component host's, found by pid", "[logs]") {
  LogFolder logs;
  logs.write("ComponentHost_GPP.log", "hosted\n");
  auto r = request("Hosted_1");
  r.pid = 77;
  auto read =
      read_log(logs.dir, r,
               {{77, "App/ComponentHost_GPP", (logs.dir / "App/ComponentHost_GPP.log").string()}});
  REQUIRE(read.has_value());
  CHECK(read->text == "hosted\n");
  r.pid = 78;
  CHECK(read_log(logs.dir, r, {}).error().status == rsca::protocol::Status::NotFound);
}

TEST_CASE("names that are paths or missing logs are refused", "[logs]") {
  LogFolder logs;
  logs.write("Comp_1.log", "x\n");
  CHECK(read_log(logs.dir, request("../App/Comp_1"), {}).error().status ==
        rsca::protocol::Status::BadRequest);
  CHECK(read_log(logs.dir, {"..", "Comp_1", {}, {}, {}}, {}).error().status ==
        rsca::protocol::Status::BadRequest);
  CHECK(read_log(logs.dir, request("Nobody"), {}).error().status ==
        rsca::protocol::Status::NotFound);
}

TEST_CASE("log text becomes valid UTF-8, keeping what already is", "[logs]") {
  CHECK(utf8_or_replaced("plain é ✓ 😀") == "plain é ✓ 😀");
  CHECK(utf8_or_replaced("a\xFF"
                         "b") == "a\xEF\xBF\xBD"
                                 "b");
  CHECK(utf8_or_replaced("\xC3") == "\xEF\xBF\xBD");                         // cut short
  CHECK(utf8_or_replaced("\xC0\xAF") == "\xEF\xBF\xBD\xEF\xBF\xBD");         // overlong
  CHECK(utf8_or_replaced("\xED\xA0\x80").find("\xED") == std::string::npos); // a surrogate
}

TEST_CASE("a log past its bound is rotated to LOG.1 and emptied, one under it is left", "[logs]") {
  LogFolder logs;
  logs.write("Comp_1.log", "0123456789\n");
  CHECK_FALSE(*rotate_if_over(logs.dir / "App/Comp_1.log", 11));
  CHECK_FALSE(*rotate_if_over(logs.dir / "App/Comp_1.log", 0)); // 0: never
  CHECK(*rotate_if_over(logs.dir / "App/Comp_1.log", 10));
  CHECK(fs::file_size(logs.dir / "App/Comp_1.log") == 0);
  CHECK(fs::file_size(logs.dir / "App/Comp_1.log.1") == 11);
}

TEST_CASE("reading a log goes across its rotation", "[logs]") {
  LogFolder logs;
  const auto log = logs.dir / "App/Comp_1.log";
  logs.write("Comp_1.log", "first\nsecond\n");
  auto before = read_log(logs.dir, request("Comp_1"), {});
  REQUIRE(before.has_value());
  logs.append("Comp_1.log", "third\n");
  REQUIRE(*rotate_if_over(log, 10));
  logs.append("Comp_1.log", "fourth\n");
  // A follower reads what it had not: the rest of LOG.1, then the log from its start.
  auto r = request("Comp_1");
  r.offset = before->next;
  auto followed = read_log(logs.dir, r, {});
  REQUIRE(followed.has_value());
  CHECK(followed->text == "third\nfourth\n");
  CHECK(followed->next == 7);
  // A tail longer than the log begins in LOG.1.
  auto tail = read_log(logs.dir, request("Comp_1"), {});
  REQUIRE(tail.has_value());
  CHECK(tail->text == "first\nsecond\nthird\nfourth\n");
  CHECK(tail->next == 7);
}

TEST_CASE("an exit report's log tail: the last lines, bounded in lines and bytes, an unended last "
          "line kept",
          "[logs]") {
  using rsca::node::log_tail;
  LogFolder logs;
  const auto log = logs.dir / "App" / "Comp_1.log";
  CHECK(log_tail(log, 0, 20, 4096).empty()); // no log
  std::string text;
  for (int i = 1; i <= 30; ++i)
    text += fmt::format("line {}\n", i);
  logs.write("Comp_1.log", text + "dying words");
  const auto tail = log_tail(log, 0, 5, 4096);
  CHECK(tail == "line 27\nline 28\nline 29\nline 30\ndying words\n");
  // Bytes bound it before lines do: whole lines only, the last ones.
  CHECK(log_tail(log, 0, 20, 20) == "line 30\ndying words\n");
  // A last line longer than the bound is cut from its start, on a character's boundary.
  logs.write("Comp_1.log", "short\n" + std::string(10, 'x') + "\xC3\xA9" + "end\n");
  CHECK(log_tail(log, 0, 20, 6) == "\xC3\xA9"
                                   "end\n");
  CHECK(log_tail(log, 0, 20, 5) == "end\n");
  // Bytes that are no UTF-8 are replaced: the tail travels as JSON text.
  logs.write("Comp_1.log", "bad \xFF byte\n");
  CHECK(log_tail(log, 0, 20, 4096) == "bad \xEF\xBF\xBD byte\n");
  // Only what the process wrote from where it began: an earlier launch's lines stay out, unless
  // the log was rotated since (shorter than where it began).
  logs.write("Comp_1.log", "earlier launch\nthis one\n");
  CHECK(log_tail(log, 15, 20, 4096) == "this one\n");
  CHECK(log_tail(log, 1000, 20, 4096) == "earlier launch\nthis one\n");
}

TEST_CASE("logs no running process writes are deleted once old, with the folders they leave "
          "empty, while a running process's, a fresh one and the daemon's own stay",
          "[logs]") {
  using rsca::node::sweep_logs;
  LogFolder logs;
  fs::create_directories(logs.dir / "Gone");
  const auto old = fs::file_time_type::clock::now() - std::chrono::hours(25);
  const auto write_old = [&](const fs::path &file) {
    std::ofstream(file) << "x\n";
    fs::last_write_time(file, old);
  };
  write_old(logs.dir / "Gone" / "Comp_1.log");
  write_old(logs.dir / "Gone" / "Comp_1.log.1");
  write_old(logs.dir / "App" / "Running_1.log"); // a quiet running process's
  write_old(logs.dir / "App" / "Old_1.log");
  logs.write("Fresh_1.log", "y\n");
  write_old(logs.dir / "rsca-noded.node1.log");
  const std::vector<op::ProcessRecord> running{
      {42, "App/Running_1", (logs.dir / "App" / "Running_1.log").string()}};
  CHECK(sweep_logs(logs.dir, running, std::chrono::hours(24)) == 3);
  CHECK_FALSE(fs::exists(logs.dir / "Gone"));
  CHECK_FALSE(fs::exists(logs.dir / "App" / "Old_1.log"));
  CHECK(fs::exists(logs.dir / "App" / "Running_1.log"));
  CHECK(fs::exists(logs.dir / "App" / "Fresh_1.log"));
  CHECK(fs::exists(logs.dir / "rsca-noded.node1.log"));
  // Kept longer than they are old: nothing goes.
  write_old(logs.dir / "App" / "Old_1.log");
  CHECK(sweep_logs(logs.dir, {}, std::chrono::hours(48)) == 0);
  CHECK(fs::exists(logs.dir / "App" / "Old_1.log"));
}
