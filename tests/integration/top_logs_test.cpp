// rsca top and rsca logs against real daemons: the figures and the logs come from the nodes that
// run the processes (node.top, node.logs), the domain daemon's figures from itself (domain.top).
#include <catch2/catch.hpp>

#include <csignal>
#include <fstream>
#include <iterator>
#include <sstream>
#include <tuple>

#include "domain_fixture.hpp"

using namespace rsca::test;

namespace {

Json top_json(TestDomain &domain, const std::vector<std::string> &more = {}) {
  std::vector<std::string> args{"top", "--json"};
  args.insert(args.end(), more.begin(), more.end());
  auto [rc, out] = domain.cli(args);
  INFO(out);
  REQUIRE(rc == 0);
  return Json::parse(out);
}

// The row of `what` (rsca-noded, APP/COMP...) on `node`; null when there is none.
Json row_of(const Json &top, const std::string &node, const std::string &what) {
  for (const auto &row : top.at("processes"))
    if (row.at("node") == node && row.at("what") == what)
      return row;
  return nullptr;
}

// How `rsca top` lists node `node` when it has no figures of it; null when it does not.
Json unreachable_row(const Json &top, const std::string &node) {
  for (const auto &row : top.at("unreachable"))
    if (row.at("node") == node)
      return row;
  return nullptr;
}

// The line of `text` that starts with `prefix`; empty when none does.
std::string line_starting(const std::string &text, const std::string &prefix) {
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);)
    if (line.rfind(prefix, 0) == 0)
      return line;
  return {};
}

void check_sane(const Json &row) {
  INFO(row.dump());
  CHECK(row.at("pid").get<long>() > 0);
  CHECK(row.at("rss_bytes").get<std::uint64_t>() > 0);
  CHECK(row.at("threads").get<std::uint64_t>() >= 1);
  CHECK(row.at("cpu_percent").get<double>() >= 0);
}

// `rsca logs TARGET --since` keeps `line`, logged as the target started, while it is recent, and
// leaves it out once the second it was logged in is over.
void check_since(TestDomain &domain, const std::string &target, const std::string &line) {
  auto [rc, out] = domain.cli({"logs", target, "--since", "3600s"});
  INFO(out);
  CHECK(rc == 0);
  CHECK(out.find(line) != std::string::npos);
  // Only an answer counts: a failed command prints no line either.
  int recent_rc = -1;
  std::string recent;
  CHECK(TestDomain::wait_for([&] {
    std::tie(recent_rc, recent) = domain.cli({"logs", target, "--since", "0s"});
    return recent_rc == 0 && recent.find(line) == std::string::npos;
  }));
  INFO(recent);
  CHECK(recent_rc == 0);
}

} // namespace

TEST_CASE("rsca top lists the daemons and every component process with the pid app.show gives",
          "[integration][top]") {
  TestDomain domain(2);
  const Json app = domain.launch_shipped("ProducerConsumer");
  const Json top = top_json(domain);
  INFO(top.dump(2));
  CHECK(top.at("unreachable").empty());
  const Json domaind = row_of(top, "domain", "rsca-domaind");
  REQUIRE(domaind.is_object());
  check_sane(domaind);
  for (const char *node : {"node1", "node2"}) {
    const Json noded = row_of(top, node, "rsca-noded");
    REQUIRE(noded.is_object());
    check_sane(noded);
  }
  for (const auto &c : app.at("components")) {
    const std::string what = "ProducerConsumer/" + c.at("id").get<std::string>();
    const Json row = row_of(top, c.at("node").get<std::string>(), what);
    REQUIRE(row.is_object());
    check_sane(row);
    CHECK(row.at("pid") == c.at("pid"));
    CHECK(row.at("application") == "ProducerConsumer");
  }
  // With an application: its processes only; an application that does not run is not found.
  const Json only = top_json(domain, {"ProducerConsumer"});
  CHECK(only.at("processes").size() == app.at("components").size());
  auto [rc, out] = domain.cli({"top", "NoSuchApp"});
  INFO(out);
  CHECK(rc == 3);
}

TEST_CASE("rsca top lists a node that does not answer as unreachable, and still once the domain "
          "lost it, with the other rows",
          "[integration][top]") {
  TestDomain domain(2);
  const Json app = domain.launch_shipped("ProducerConsumer", {"--strategy", "spread"});
  // What node1 runs, and the domain daemon, are shown whatever node2 does; node2 has no row.
  auto check_others = [&](const Json &top) {
    INFO(top.dump(2));
    CHECK(row_of(top, "domain", "rsca-domaind").is_object());
    CHECK(row_of(top, "node1", "rsca-noded").is_object());
    for (const auto &row : top.at("processes"))
      CHECK(row.at("node") != "node2");
    for (const auto &c : app.at("components"))
      if (c.at("node") == "node1")
        CHECK(
            row_of(top, "node1", "ProducerConsumer/" + c.at("id").get<std::string>()).is_object());
    const Json node2 = unreachable_row(top, "node2");
    REQUIRE(node2.is_object());
    CHECK_FALSE(node2.at("error").get<std::string>().empty());
    CHECK(unreachable_row(top, "node1").is_null());
    return node2;
  };
  FrozenNode frozen(domain, 2);
  // Within its lease the domain still lists it: it is asked, and does not answer in time.
  // (Should the lease run out first, it is listed as lost instead: unreachable all the same.)
  check_others(top_json(domain, {"--timeout-ms", "1000"}));
  // Past its lease the domain loses it, and keeps its devices and components: it is listed as
  // lost, not left out.
  REQUIRE(TestDomain::wait_for([&] {
    auto nodes = domain.call("domain.nodes");
    return nodes && nodes->at("nodes").size() == 1 && nodes->at("lost").size() == 1;
  }));
  const Json lost = check_others(top_json(domain));
  CHECK(lost.at("lost") == true);
  auto [rc, listed] = domain.cli({"ls", "nodes"});
  INFO(listed);
  CHECK(rc == 0);
  CHECK_THAT(line_starting(listed, "node2 "), Catch::Contains(" lost "));
  // Back (the same run): asked and shown again, nothing unreachable.
  frozen.resume();
  Json back;
  CHECK(TestDomain::wait_for([&] {
    back = top_json(domain);
    return back.at("unreachable").empty() && row_of(back, "node2", "rsca-noded").is_object();
  }));
  INFO(back.dump(2));
}

TEST_CASE("rsca top shows a component that burns a CPU as busy", "[integration][top]") {
  TestDomain domain(1);
  const Json app = domain.create("Busy");
  const long pid = pid_of(app, "Burner_1");
  REQUIRE(pid > 0);
  // Each rsca top is a reading; CPU % is since the node's previous one. The node daemon beside
  // the burner is busy while it starts the component, idle after: one reading shows both.
  double seen = 0;
  double node = 0;
  const bool busy = TestDomain::wait_for(
      [&] {
        const Json top = top_json(domain);
        const Json row = row_of(top, "node1", "Busy/Burner_1");
        const Json noded = row_of(top, "node1", "rsca-noded");
        if (!row.is_object() || !noded.is_object() || row.at("pid") != pid)
          return false;
        seen = row.at("cpu_percent").get<double>();
        node = noded.at("cpu_percent").get<double>();
        return seen > 20.0 && seen > 2 * node;
      },
      20s);
  INFO("last CPU %: " << seen << ", the node daemon's " << node);
  CHECK(busy);
}

TEST_CASE("rsca logs prints what a component logged, read by its node", "[integration][logs]") {
  TestDomain domain(2);
  domain.launch_shipped("ProducerConsumer");
  auto [rc, out] = domain.cli({"logs", "ProducerConsumer/Producer_1"});
  INFO(out);
  CHECK(rc == 0);
  CHECK(out.find("serving at") != std::string::npos);
  auto [jrc, jout] = domain.cli({"logs", "ProducerConsumer/Producer_1", "--json", "-n", "5"});
  INFO(jout);
  REQUIRE(jrc == 0);
  std::size_t lines = 0;
  std::istringstream in(jout);
  for (std::string line; std::getline(in, line); ++lines) {
    const Json parsed = Json::parse(line);
    CHECK(parsed.at("component") == "Producer_1");
    CHECK(parsed.contains("line"));
  }
  CHECK(lines >= 1);
  CHECK(lines <= 5);
  // Every component of the application, each line marked with its component.
  auto [arc, aout] = domain.cli({"logs", "ProducerConsumer"});
  INFO(aout);
  CHECK(arc == 0);
  CHECK(aout.find("Consumer_1 | ") != std::string::npos);
}

TEST_CASE("rsca logs of a component or an application that does not exist is not found",
          "[integration][logs]") {
  TestDomain domain(1);
  domain.launch_shipped("ProducerConsumer");
  auto [rc, out] = domain.cli({"logs", "ProducerConsumer/Nobody_9"});
  INFO(out);
  CHECK(rc == 3);
  auto [arc, aout] = domain.cli({"logs", "NoSuchApp"});
  INFO(aout);
  CHECK(arc == 3);
  CHECK(aout.find("no application or node NoSuchApp") != std::string::npos);
}

TEST_CASE("rsca logs --since leaves out older lines", "[integration][logs]") {
  TestDomain domain(1);
  domain.launch_shipped("ProducerConsumer");
  check_since(domain, "ProducerConsumer/Producer_1", "serving at");
  CHECK(domain.cli({"logs", "ProducerConsumer/Producer_1", "--since", "soon"}).first == 2);
}

TEST_CASE("rsca logs NODE --since leaves out the node's older lines", "[integration][logs]") {
  TestDomain domain(1);
  check_since(domain, "node1", "node node1 announced");
}

TEST_CASE("rsca logs -f goes on printing what the component logs", "[integration][logs]") {
  TestDomain domain(1);
  domain.launch_shipped("ProducerConsumer");
  const fs::path out = domain.run_dir() / "follow.out";
  ChildProcess follow((kBin / "rsca").string(), {"logs", "-f", "ProducerConsumer/Producer_1"},
                      domain.env(), out);
  auto text = [&] {
    std::ifstream in(out);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  REQUIRE(TestDomain::wait_for([&] { return text().find("serving at") != std::string::npos; }));
  CHECK(text().find("stopped") == std::string::npos);
  REQUIRE(domain.call("app.stop", Json{{"app", "ProducerConsumer"}}).has_value());
  CHECK(TestDomain::wait_for([&] { return text().find("stopped") != std::string::npos; }));
  INFO(text());
  follow.signal(SIGINT);
  CHECK(follow.wait_exit(5s).has_value());
}
