// The synthetic applications of tools/gen-app launch on a real domain: every connection matched
// before start (the connect step waits for it), everything gone after release.
#include <set>

#include "domain_fixture.hpp"

using namespace rsca::test;
using namespace std::chrono_literals;

TEST_CASE("synthetic applications (chain, tree, random graph, as processes or in component hosts) "
          "launch connected and release clean",
          "[integration][synthetic]") {
  TestDomain domain(2);
  const auto shape = GENERATE(std::string("chain"), std::string("tree"), std::string("random"));
  const bool hosted = GENERATE(false, true);
  const fs::path sdr = domain.run_dir() / "synthetic";
  std::vector<std::string> args{"--shape", shape, "--components", "12", "--out", sdr.string()};
  if (hosted)
    args.emplace_back("--shared-library");
  ChildProcess gen((kSource / "tools/gen-app").string(), args, {});
  auto generated = gen.wait_exit(30s);
  REQUIRE(generated.has_value());
  REQUIRE(WEXITSTATUS(*generated) == 0);
  const std::string name =
      std::string(1, static_cast<char>(std::toupper(shape[0]))) + shape.substr(1) + "12";
  const fs::path sad = sdr / "dom/waveforms" / name / (name + ".sad.xml");
  auto [rc, out] = domain.cli({"launch", sad.string()});
  INFO(out);
  REQUIRE(rc == 0);
  auto app = domain.call("app.show", Json{{"app", name}});
  REQUIRE(app.has_value());
  CHECK(app->at("components").size() == 12);
  // A process per component, or one component host per device used.
  std::set<long> processes;
  std::set<std::string> devices;
  for (const auto &c : app->at("components")) {
    processes.insert(c.at("pid").get<long>());
    devices.insert(c.at("device").get<std::string>());
  }
  CHECK(processes.size() == (hosted ? devices.size() : 12));
  // A chain and a tree of 12 have 11 connections; the random graph at least that many.
  CHECK(app->at("connections").size() >= 11);
  auto list = domain.call("connection.list", Json{{"app", name}});
  REQUIRE(list.has_value());
  for (const auto &c : list->at("connections")) {
    INFO(c.dump());
    CHECK(c.at("uses_state").at("matched") == 1);
    CHECK(c.at("provides_state").at("matched").get<int>() >= 1);
  }
  REQUIRE(domain.call("app.release", Json{{"app", name}}).has_value());
  domain.require_clean(pids_of(*app));
}
