// `rsca show APP --graph dot|svg` against a real domain: the picture names every component in
// its node's and device's cluster, every connection with its QoS and live state, the event
// channels; Graphviz's dot really draws it as SVG.
#include <signal.h>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <fstream>
#include <iterator>

#include "domain_fixture.hpp"

using namespace rsca::test;
using rsca::control::Json;

namespace {

// `text` as a DOT string: these names hold nothing to escape.
std::string dot_quoted(const std::string &text) {
  return "\"" + text + "\"";
}

std::string read_all(const fs::path &file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The application's picture as DOT, by the CLI.
std::string dot_of(TestDomain &domain, const std::string &app) {
  auto [rc, out] = domain.cli({"show", app, "--graph", "dot"});
  INFO(out);
  REQUIRE(rc == 0);
  return out;
}

} // namespace

TEST_CASE("rsca show --graph draws a launched application: clusters per node and device, its "
          "components and connection, and dot makes it SVG",
          "[integration][graph]") {
  TestDomain domain(2);
  const Json app = domain.launch_shipped("ProducerConsumer", {"--strategy", "spread"});
  INFO(app.dump());

  const std::string dot = dot_of(domain, "ProducerConsumer");
  INFO(dot);
  CHECK(dot.rfind("digraph \"ProducerConsumer\" {", 0) == 0);
  for (const auto &c : app.at("components")) {
    const std::string id = c.at("id"), node = c.at("node"), device = c.at("device");
    CHECK(dot.find("label=" + dot_quoted(node) + ";") != std::string::npos);   // node's cluster
    CHECK(dot.find("label=" + dot_quoted(device) + ";") != std::string::npos); // device's cluster
    CHECK(dot.find("[label=\"" + id + "\\nrunning") != std::string::npos);
  }
  // The SAD's one connection, matched at launch, with the QoS the SAD gives it.
  CHECK(dot.find("samples (connected)\\nsamples_out -> samples_in\\nreliable, keeplast(16), "
                 "deadline 100ms") != std::string::npos);
  CHECK(dot.find("samples_tap\\nexternal uses port") != std::string::npos);

  const fs::path svg = domain.run_dir() / "ProducerConsumer.svg";
  auto [rc, out] = domain.cli({"show", "ProducerConsumer", "--graph", "svg", "-o", svg.string()});
  INFO(out);
  REQUIRE(rc == 0);
  const std::string drawn = read_all(svg);
  CHECK(drawn.rfind("<?xml", 0) == 0);
  CHECK(drawn.find("<svg") != std::string::npos);
  for (const auto &c : app.at("components"))
    CHECK(drawn.find(">" + c.at("id").get<std::string>() + "</text>") != std::string::npos);

  REQUIRE(domain.call("app.release", Json{{"app", "ProducerConsumer"}}).has_value());
  domain.require_clean(pids_of(app));
}

TEST_CASE("rsca show --graph draws an event channel between its members, and a connection whose "
          "component died as failed",
          "[integration][graph]") {
  TestDomain domain;
  const Json app = domain.create("Events");
  INFO(app.dump());

  const std::string dot = dot_of(domain, "Events");
  INFO(dot);
  CHECK(dot.find("[label=\"Ticks\\nevent channel\", shape=hexagon") != std::string::npos);
  CHECK(dot.find("publish (connected)\\nevents_out -> channel") != std::string::npos);
  CHECK(dot.find("all (connected)\\nchannel -> events_in") != std::string::npos);
  CHECK(dot.find("filter sequence < 50") != std::string::npos);

  const long victim = pid_of(app, "Consumer_2");
  REQUIRE(victim > 0);
  REQUIRE(::kill(static_cast<pid_t>(victim), SIGKILL) == 0);
  std::string after;
  CHECK(TestDomain::wait_for([&] {
    after = dot_of(domain, "Events");
    return after.find("first_fifty (failed)") != std::string::npos;
  }));
  INFO(after);
  CHECK(after.find("all (connected)") != std::string::npos);
  CHECK(after.find("Consumer_2\\nexited") != std::string::npos);

  REQUIRE(domain.call("app.release", Json{{"app", "Events"}}).has_value());
  domain.require_clean(pids_of(app));
}
