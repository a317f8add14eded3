// Unit tests of the ResourceAllocator's reservations (allocator/resource_allocator.hpp): a release
// gives back what its reservation still holds, never a share a device that went away and came
// back never gave it (issue 18, defect 4). Pure: hand-made devices and packages, no domain.
#include "allocator/resource_allocator.hpp"

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

using namespace rsca;
using namespace rsca::allocator;

namespace {

using PkgPtr = std::shared_ptr<const profile::ResolvedSoftPkg>;

// A package of one implementation that takes `utilization` of a CPU.
PkgPtr softpkg(const std::string &name, double utilization) {
  auto spd = std::make_shared<profile::SoftPkg>();
  spd->id = spd->name = name;
  profile::Implementation impl;
  impl.id = "cpp";
  impl.resource_demand.emplace();
  impl.resource_demand->utilization = utilization;
  spd->implementations.push_back(std::move(impl));
  auto pkg = std::make_shared<profile::ResolvedSoftPkg>();
  pkg->spd_path = name + ".spd.xml";
  pkg->spd = spd;
  pkg->implementations.push_back({&spd->implementations[0], nullptr, {}});
  return pkg;
}

// A GPP of one CPU (100 % cpu_capacity).
Device one_cpu_gpp(const std::string &node) {
  Device d;
  d.id = node + ":GPP";
  d.node = node;
  d.kind = "gpp";
  d.capacity[kCpuCapacity] = 100;
  return d;
}

ComponentRequest pinned(std::string instance, const PkgPtr &pkg, std::string device) {
  ComponentRequest c;
  c.instance = std::move(instance);
  c.softpkg = pkg.get();
  c.device = std::move(device);
  return c;
}

// A periodic component (T = 10 ms, C = 2 ms: 20 % of a CPU) pinned to `device`.
ComponentRequest periodic(std::string instance, const PkgPtr &pkg, std::string device) {
  ComponentRequest c = pinned(std::move(instance), pkg, std::move(device));
  c.timing.emplace();
  c.timing->period = Duration{std::chrono::milliseconds(10)};
  c.timing->execution_time = Duration{std::chrono::milliseconds(2)};
  return c;
}

double cpu_allocated(const ResourceAllocator &allocator, const std::string &device) {
  const auto state = allocator.snapshot();
  const auto &allocated = state.at(device).load.allocated;
  auto it = allocated.find(kCpuCapacity);
  return it == allocated.end() ? 0.0 : it->second;
}

std::size_t tasks_on(const ResourceAllocator &allocator, const std::string &device) {
  const auto state = allocator.snapshot();
  std::size_t n = 0;
  for (const auto &cpu : state.at(device).load.cpu_tasks)
    n += cpu.size();
  return n;
}

// An allocator of two nodes of one GPP each, and a package of a 30 % component.
struct TwoNodes {
  TwoNodes() {
    allocator.set_node_devices("n1", {one_cpu_gpp("n1")});
    allocator.set_node_devices("n2", {one_cpu_gpp("n2")});
  }
  PkgPtr pkg = softpkg("worker", 0.3);
  ResourceAllocator allocator;
};

// An application of a 30 % component on n1 and a periodic one (20 %) on n2, by the same
// instance names each time: equal tasks, as two launches of one SAD give.
PlanRequest spread_app(const PkgPtr &pkg) {
  PlanRequest request;
  request.components = {pinned("a", pkg, "n1:GPP"), periodic("p", pkg, "n2:GPP")};
  return request;
}

} // namespace

TEST_CASE_METHOD(TwoNodes,
                 "allocator: a release after a node came back gives back only what the application "
                 "still holds",
                 "[allocator]") {
  const auto a = allocator.allocate(spread_app(pkg), {});
  REQUIRE(a.has_value());
  CHECK(cpu_allocated(allocator, "n2:GPP") == Approx(20));

  // n2 goes (its components die with it) and comes back empty.
  allocator.remove_node("n2");
  allocator.set_node_devices("n2", {one_cpu_gpp("n2")});
  CHECK(cpu_allocated(allocator, "n2:GPP") == Approx(0).margin(1e-9));

  // B is placed on the new n2; then A is released.
  PlanRequest b_request;
  b_request.components = {periodic("p", pkg, "n2:GPP")};
  const auto b = allocator.allocate(b_request, {});
  REQUIRE(b.has_value());
  allocator.release(*a);

  // n2 still holds B's 20 % and B's task; n1 is free again.
  CHECK(cpu_allocated(allocator, "n2:GPP") == Approx(20));
  CHECK(tasks_on(allocator, "n2:GPP") == 1);
  CHECK(cpu_allocated(allocator, "n1:GPP") == Approx(0).margin(1e-9));
  CHECK(allocator.reservations() == 1);

  allocator.release(*b);
  CHECK(cpu_allocated(allocator, "n2:GPP") == Approx(0).margin(1e-9));
  CHECK(tasks_on(allocator, "n2:GPP") == 0);
  CHECK(allocator.reservations() == 0);
}

TEST_CASE_METHOD(
    TwoNodes,
    "allocator: a device the node stops announcing takes its part of every reservation "
    "along",
    "[allocator]") {
  const auto a = allocator.allocate(spread_app(pkg), {});
  REQUIRE(a.has_value());
  // n2 announces itself without its GPP, then with it again (no remove_node in between).
  Device other = one_cpu_gpp("n2");
  other.id = "n2:GPP_2";
  allocator.set_node_devices("n2", {other});
  allocator.set_node_devices("n2", {other, one_cpu_gpp("n2")});
  CHECK(cpu_allocated(allocator, "n2:GPP") == Approx(0).margin(1e-9));
  PlanRequest b_request;
  b_request.components = {pinned("b", pkg, "n2:GPP")};
  REQUIRE(allocator.allocate(b_request, {}).has_value());
  allocator.release(*a);
  CHECK(cpu_allocated(allocator, "n2:GPP") == Approx(30));
}

TEST_CASE_METHOD(TwoNodes,
                 "allocator: a node that re-announces itself keeps the reservations on it",
                 "[allocator]") {
  const auto a = allocator.allocate(spread_app(pkg), {});
  REQUIRE(a.has_value());
  allocator.set_node_devices("n2", {one_cpu_gpp("n2")}); // the same devices again
  CHECK(cpu_allocated(allocator, "n2:GPP") == Approx(20));
  allocator.release(*a);
  CHECK(cpu_allocated(allocator, "n2:GPP") == Approx(0).margin(1e-9));
  CHECK(tasks_on(allocator, "n2:GPP") == 0);
}

TEST_CASE_METHOD(
    TwoNodes,
    "allocator: a plan is given back once, and one that reserved nothing gives back nothing",
    "[allocator]") {
  PlanRequest request;
  request.components = {pinned("a", pkg, "n1:GPP")};
  const auto first = allocator.allocate(request, {});
  const auto second = allocator.allocate(request, {});
  REQUIRE(first.has_value());
  REQUIRE(second.has_value());
  CHECK(first->allocation != second->allocation);
  CHECK(cpu_allocated(allocator, "n1:GPP") == Approx(60));

  allocator.release(*first);
  allocator.release(*first); // twice: the second time it holds nothing
  CHECK(cpu_allocated(allocator, "n1:GPP") == Approx(30));

  const auto planned = allocator.plan(request, {});
  REQUIRE(planned.has_value());
  CHECK(planned->allocation == 0);
  allocator.release(*planned);
  CHECK(cpu_allocated(allocator, "n1:GPP") == Approx(30));
}

TEST_CASE_METHOD(TwoNodes,
                 "allocator: a lost node keeps its reservations and takes no placement until it "
                 "is back",
                 "[allocator]") {
  const auto a = allocator.allocate(spread_app(pkg), {});
  REQUIRE(a.has_value());
  allocator.suspend_node("n2");
  CHECK(cpu_allocated(allocator, "n2:GPP") == Approx(20)); // its processes may still run

  PlanRequest on_n2;
  on_n2.components = {pinned("b", pkg, "n2:GPP")};
  CHECK_FALSE(allocator.plan(on_n2, {}).has_value());
  CHECK_FALSE(allocator.allocate(on_n2, {}).has_value());
  PlanRequest anywhere;
  anywhere.components = {pinned("b", pkg, "n1:GPP")};
  anywhere.components[0].device.reset(); // the planner chooses
  const auto elsewhere = allocator.plan(anywhere, {});
  REQUIRE(elsewhere.has_value());
  CHECK(elsewhere->placements.at(0).device == "n1:GPP");

  // Back, the same run: its share is still A's, and it takes placements again.
  allocator.set_node_devices("n2", {one_cpu_gpp("n2")});
  CHECK(cpu_allocated(allocator, "n2:GPP") == Approx(20));
  const auto b = allocator.allocate(on_n2, {});
  REQUIRE(b.has_value());
  CHECK(cpu_allocated(allocator, "n2:GPP") == Approx(50));
  allocator.release(*a);
  allocator.release(*b);
  CHECK(cpu_allocated(allocator, "n2:GPP") == Approx(0).margin(1e-9));
  CHECK(allocator.reservations() == 0);
}
