// rsca logs NODE against real daemons: a node daemon's own log, kept in its log folder and read by
// that node (node.daemon_logs); and a component's log read across its rotation (node.logs).
#include <catch2/catch.hpp>

#include <algorithm>
#include <csignal>
#include <fstream>
#include <iterator>
#include <sstream>

#include "domain_fixture.hpp"

using namespace rsca::test;

namespace {

std::string text_of(const fs::path &file) {
  std::ifstream in(file);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::vector<std::string> lines_of(const std::string &text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    lines.push_back(line);
  return lines;
}

// The line the node logs when it has started a component process, with the pid it got.
std::string started_line(const Json &app, const std::string &component) {
  return fmt::format("{}/{} (pid {}) started", app.at("name").get<std::string>(), component,
                     pid_of(app, component));
}

// The number a Faulty component's chatter line carries; -1 for another line.
long chatter_number(const std::string &line) {
  const auto at = line.find("chatter ");
  return at == std::string::npos ? -1 : std::stol(line.substr(at + 8, 6));
}

} // namespace

TEST_CASE("rsca logs NODE prints the node daemon's own log, read by that node",
          "[integration][logs]") {
  TestDomain domain(2);
  const Json app = domain.launch_shipped("ProducerConsumer", {"--strategy", "spread"});
  const std::string node = app.at("components").at(0).at("node");
  const std::string component = app.at("components").at(0).at("id");
  CHECK(fs::is_regular_file(domain.run_dir() / "logs" / fmt::format("rsca-noded.{}.log", node)));
  auto [rc, out] = domain.cli({"logs", node, "-n", "1000"});
  INFO(out);
  CHECK(rc == 0);
  CHECK(out.find(fmt::format("node {} announced", node)) != std::string::npos);
  CHECK(out.find(started_line(app, component)) != std::string::npos);
  // Each node serves its own log only: the other node did not start that process.
  const std::string other = node == "node1" ? "node2" : "node1";
  auto [orc, oout] = domain.cli({"logs", "node:" + other, "-n", "1000"});
  INFO(oout);
  CHECK(orc == 0);
  CHECK(oout.find(fmt::format("node {} announced", other)) != std::string::npos);
  CHECK(oout.find(started_line(app, component)) == std::string::npos);
  // --json: a JSON object per line, naming the node; -n bounds them.
  auto [jrc, jout] = domain.cli({"logs", node, "--json", "-n", "3"});
  INFO(jout);
  REQUIRE(jrc == 0);
  const auto json_lines = lines_of(jout);
  CHECK(json_lines.size() == 3);
  for (const auto &line : json_lines) {
    const Json parsed = Json::parse(line);
    CHECK(parsed.at("node") == node);
    CHECK(parsed.contains("line"));
  }
}

TEST_CASE("rsca logs of a name no application and no node has exits 3", "[integration][logs]") {
  TestDomain domain(1);
  for (const char *target : {"nobody", "node:nobody", "node:ProducerConsumer"}) {
    auto [rc, out] = domain.cli({"logs", target});
    INFO(target << ": " << out);
    CHECK(rc == 3);
  }
}

TEST_CASE("rsca logs -f NODE goes on printing what the node logs", "[integration][logs]") {
  TestDomain domain(1);
  const fs::path out = domain.run_dir() / "follow.out";
  ChildProcess follow((kBin / "rsca").string(), {"logs", "-f", "node1"}, domain.env(), out);
  REQUIRE(TestDomain::wait_for(
      [&] { return text_of(out).find("node node1 announced") != std::string::npos; }));
  const Json app = domain.launch_shipped("ProducerConsumer");
  const std::string started = started_line(app, "Producer_1");
  CHECK(TestDomain::wait_for([&] { return text_of(out).find(started) != std::string::npos; }));
  INFO(text_of(out));
  follow.signal(SIGINT);
  CHECK(follow.wait_exit(5s).has_value());
}

TEST_CASE("rsca logs APP/COMP reads the newest lines across the log's rotation",
          "[integration][logs]") {
  TestDomain domain(std::vector<fs::path>{});
  domain.start_node(TestDomain::shipped_nodes(1)[0], {"--log-max-kib", "16"});
  const Json app = domain.create("Chatty");
  const fs::path log = domain.run_dir() / "logs" / "Chatty" / "Talker_1.log";
  const fs::path previous = log.string() + ".1";
  REQUIRE(fs::is_regular_file(log));
  // ~26 KiB of lines: past the bound, rotated within the node's next look (a second). A look in
  // the middle of them leaves the rest (under 16 KiB, never rotated again) in the log.
  REQUIRE(domain.cli({"configure", "Chatty/Talker_1", "chatter=120"}).first == 0);
  REQUIRE(TestDomain::wait_for([&] { return fs::exists(previous); }, 20s));
  // Ten more in the log, after those rotated.
  REQUIRE(domain.cli({"configure", "Chatty/Talker_1", "chatter=10"}).first == 0);
  const auto older = lines_of(text_of(previous));
  const auto newer = lines_of(text_of(log));
  REQUIRE(!older.empty());
  REQUIRE(!newer.empty());
  CHECK(fs::file_size(log) < 16 * 1024); // nothing rotates the files as they are read
  auto [rc, out] = domain.cli({"logs", "Chatty/Talker_1", "-n", "100"});
  INFO(out);
  REQUIRE(rc == 0);
  const auto shown = lines_of(out);
  // The last 100 lines of the two files, the older one's first.
  std::vector<std::string> both = older;
  both.insert(both.end(), newer.begin(), newer.end());
  REQUIRE(both.size() > 100);
  const std::vector<std::string> expected(both.end() - 100, both.end());
  CHECK(shown == expected);
  // They span the rotation: some from LOG.1 (over 70 lines of ~220 bytes past 16 KiB), the
  // newest last, in order.
  REQUIRE(!shown.empty());
  CHECK(std::find(shown.begin(), shown.end(), older.back()) != shown.end());
  CHECK(shown.back() == newer.back());
  long last = 0;
  for (const auto &line : shown)
    if (const long n = chatter_number(line); n >= 0) {
      CHECK(n > last);
      last = n;
    }
  CHECK(last == 130); // the newest chatter line (the runtime's "configured" line comes after)
}
