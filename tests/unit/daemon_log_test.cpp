// node.daemon_logs on a log folder (node/daemon_log.hpp): the node daemon's own log as spdlog's
// rotating sink writes it, read across its rotation; the request's bounds.
#include <filesystem>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <catch2/catch.hpp>

#include "node/daemon_log.hpp"
#include "temp_dir.hpp"

namespace fs = std::filesystem;
namespace op = rsca::protocol::node;
using namespace rsca::node;

namespace {

// The default logger writes to the daemon's log as well while it lives; the one before is back
// after, for the other tests.
struct LoggingToFile {
  std::shared_ptr<spdlog::logger> before = spdlog::default_logger();
  LoggingToFile(const fs::path &file, std::uint64_t max_bytes) {
    REQUIRE(log_also_to_file(file, max_bytes).has_value());
    spdlog::default_logger()->set_level(spdlog::level::info); // whatever a test before set
  }
  ~LoggingToFile() { spdlog::set_default_logger(before); }
};

} // namespace

TEST_CASE("a node daemon's own log is kept in a file, its lines stamped as a component's",
          "[logs]") {
  const rsca::test::TempDir folder;
  const auto file = daemon_log_file(folder.path(), "nodeX");
  CHECK(file == folder.path() / "rsca-noded.nodeX.log");
  {
    LoggingToFile logging(file, 0);
    spdlog::info("a line of the daemon");
  }
  auto read = read_daemon_log(folder.path(), "nodeX", {});
  REQUIRE(read.has_value());
  CHECK(read->log == "rsca-noded.nodeX.log");
  INFO(read->text);
  CHECK(read->text.rfind('[', 0) == 0); // "[YYYY-MM-DD HH:MM:SS.mmm]", what --since reads
  CHECK(read->text.substr(5, 1) == "-");
  CHECK(read->text.find("] [noded] [info] a line of the daemon\n") != std::string::npos);
  auto missing = read_daemon_log(folder.path(), "nodeY", {});
  REQUIRE_FALSE(missing.has_value());
  CHECK(missing.error().status == rsca::protocol::Status::NotFound);
}

TEST_CASE("a node daemon's own log is read across the rotation its sink makes", "[logs]") {
  const rsca::test::TempDir folder;
  const auto file = daemon_log_file(folder.path(), "nodeX");
  const fs::path older = folder.path() / "rsca-noded.nodeX.1.log"; // as spdlog names it
  std::optional<std::uint64_t> offset;
  {
    LoggingToFile logging(file, 1024);
    for (int i = 0; i < 18; ++i) // 50 bytes each: 900
      spdlog::info("line {:03}", i);
    auto first = read_daemon_log(folder.path(), "nodeX", {});
    REQUIRE(first.has_value());
    CHECK_FALSE(fs::exists(older));
    offset = first->next;
    for (int i = 18; i < 22; ++i) // the 21st would take it past 1 KiB: the sink rotates first
      spdlog::info("line {:03}", i);
  }
  REQUIRE(fs::exists(older));
  CHECK(fs::file_size(older) == 1000);
  // A follower reads on from where it was: the rest of the older file, then the log.
  op::DaemonLogsRequest follow{offset, std::nullopt};
  auto followed = read_daemon_log(folder.path(), "nodeX", follow);
  REQUIRE(followed.has_value());
  INFO(followed->text);
  CHECK(followed->text.find("line 017") == std::string::npos);
  CHECK(followed->text.find("line 018") == followed->text.find("line "));
  CHECK(followed->text.find("line 019") != std::string::npos);
  CHECK(followed->text.find("line 020") != std::string::npos);
  CHECK(followed->text.find("line 021\n") == followed->text.size() - 9);
  CHECK(followed->next == fs::file_size(file));
  // A tail longer than the log begins in the older file.
  auto tail = read_daemon_log(folder.path(), "nodeX", {});
  REQUIRE(tail.has_value());
  CHECK(tail->text.find("line 000") != std::string::npos);
  CHECK(tail->text.find("line 021\n") == tail->text.size() - 9);
  CHECK(tail->next == fs::file_size(file));
  CHECK(tail->offset == 0); // it begins before the log does
  CHECK(tail->text.size() == 1000 + fs::file_size(file));
}

TEST_CASE("node.daemon_logs refuses a max_bytes out of its bounds", "[logs]") {
  using rsca::protocol::decode;
  CHECK(decode<op::DaemonLogsRequest>(rsca::control::Json::object()).has_value());
  CHECK(decode<op::DaemonLogsRequest>({{"offset", 12}, {"max_bytes", 1}}).has_value());
  CHECK_FALSE(decode<op::DaemonLogsRequest>({{"max_bytes", 0}}).has_value());
  CHECK_FALSE(
      decode<op::DaemonLogsRequest>({{"max_bytes", op::LogsRequest::kMaxBytes + 1}}).has_value());
  CHECK_FALSE(decode<op::DaemonLogsRequest>({{"offset", -1}}).has_value());
}
