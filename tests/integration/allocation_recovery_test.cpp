// What the domain holds on a node that died and came back (issue 18, defect 4): an application
// released after its node restarted gives back only what it still holds, so the share of an
// application placed on the restarted node since stays reserved and admission cannot
// over-commit.
#include "domain_fixture.hpp"

using namespace rsca::test;

namespace {

// The CPU the domain has reserved on `device` (percent of one core).
double cpu_allocated(TestDomain &domain, const std::string &device) {
  auto devices = domain.call("domain.devices");
  REQUIRE(devices.has_value());
  for (const auto &d : devices->at("devices"))
    if (d.at("id") == device)
      return d.at("capacity").at("cpu_capacity").at("allocated").get<double>();
  FAIL("the domain has no device " << device);
  return -1;
}

std::size_t node_count(TestDomain &domain) {
  auto nodes = domain.call("domain.nodes");
  return nodes ? nodes->at("nodes").size() : 0;
}

} // namespace

TEST_CASE("a release after a node restarted frees only what the application still holds there",
          "[integration][domain][allocator][recovery]") {
  // Two nodes of one CPU each; a Greedy takes 60% of one, GreedyPair two of them.
  const auto small2 = kTestSdr / "dev/nodes/small2/DeviceManager.dcd.xml";
  TestDomain domain({kTestSdr / "dev/nodes/small1/DeviceManager.dcd.xml", small2});
  domain.install("GreedyPair");
  domain.install("Greedy");
  auto a = domain.call("app.create", Json{{"application", "GreedyPair"}});
  INFO((a ? std::string() : a.error().message));
  REQUIRE(a.has_value());
  std::vector<long> pids = pids_of(*a);
  CHECK(cpu_allocated(domain, "small1:GPP_1") == Approx(60.0)); // spread by necessity
  CHECK(cpu_allocated(domain, "small2:GPP_1") == Approx(60.0));

  // small2 dies (its component with it); the domain forgets it before it comes back empty.
  domain.kill_node(2);
  REQUIRE(TestDomain::wait_for([&] { return node_count(domain) == 1; }));
  domain.start_node(small2);
  CHECK(cpu_allocated(domain, "small2:GPP_1") == Approx(0.0).margin(1e-9));

  // B can only go to small2 (small1 has 40% free); then A is released.
  auto b = domain.call("app.create", Json{{"application", "Greedy"}, {"name", "b"}});
  INFO((b ? std::string() : b.error().message));
  REQUIRE(b.has_value());
  CHECK(b->at("components").at(0).at("node") == "small2");
  for (long pid : pids_of(*b))
    pids.push_back(pid);
  auto released = domain.call("app.release", Json{{"app", "GreedyPair"}});
  INFO((released ? std::string() : released.error().message));
  REQUIRE(released.has_value());

  // small2 still holds B's 60%: a second Greedy is refused, not placed beside B.
  CHECK(cpu_allocated(domain, "small1:GPP_1") == Approx(0.0).margin(1e-9));
  CHECK(cpu_allocated(domain, "small2:GPP_1") == Approx(60.0));
  auto plan = domain.call(
      "app.plan", Json{{"application", "Greedy"}, {"assign", {{"Greedy_1", "small2:GPP_1"}}}});
  REQUIRE(plan.has_value());
  CHECK(plan->at("admitted") == false);

  REQUIRE(domain.call("app.release", Json{{"app", "b"}}).has_value());
  domain.require_clean(pids);
}
