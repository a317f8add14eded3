// Unit tests of the placement planner (allocator/planner.hpp): one test case per constraint
// kind, each on hand-made devices and software packages, with every expected value worked out
// by hand in a comment next to it.
#include "allocator/planner.hpp"
#include "allocator/resource_allocator.hpp"
#include "planner_state.hpp"

#include <set>

#include <catch2/catch.hpp>

#include <chrono>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

using namespace rsca;
using namespace rsca::allocator;
using std::chrono::milliseconds;

namespace {

using PlanResult = tl::expected<Plan, std::vector<Rejection>>;
using PkgPtr = std::shared_ptr<const profile::ResolvedSoftPkg>;

// ---- fixture builders ---------------------------------------------------------------------------

profile::SimpleRef ref(std::string refid, std::string value) {
  profile::SimpleRef r;
  r.refid = std::move(refid);
  r.value = std::move(value);
  return r;
}

// One implementation of a package and the softpkg dependencies it resolves to (these live in
// ResolvedImplementation, not in profile::Implementation).
struct ImplSpec {
  profile::Implementation impl;
  std::vector<profile::ResolvedDependency> dependencies;

  explicit ImplSpec(std::string id) { impl.id = std::move(id); }
  ImplSpec &os(std::string name) {
    impl.os.push_back({std::move(name), ""});
    return *this;
  }
  ImplSpec &processor(std::string name) {
    impl.processors.push_back(std::move(name));
    return *this;
  }
  // Fraction of one CPU: the planner demands 100 * u percent of cpu_capacity.
  ImplSpec &utilization(double u) {
    demand().utilization = u;
    return *this;
  }
  ImplSpec &memory_mib(std::uint64_t mib) {
    demand().memory_bytes = mib * 1024 * 1024;
    return *this;
  }
  ImplSpec &needs(std::string refid, std::string value) {
    impl.property_dependencies.push_back({"matching", ref(std::move(refid), std::move(value))});
    return *this;
  }
  ImplSpec &uses(profile::UsesDevice uses) {
    impl.uses_devices.push_back(std::move(uses));
    return *this;
  }
  ImplSpec &depends_on(PkgPtr pkg, std::optional<std::string> implref = std::nullopt) {
    dependencies.push_back({std::move(pkg), std::move(implref)});
    return *this;
  }

private:
  profile::ResourceDemand &demand() {
    if (!impl.resource_demand)
      impl.resource_demand.emplace();
    return *impl.resource_demand;
  }
};

// A resolved package whose ResolvedImplementations point into the SoftPkg it shares ownership
// of, so the package stays valid as long as the returned pointer lives.
PkgPtr softpkg(const std::string &name, const std::vector<ImplSpec> &impls) {
  auto spd = std::make_shared<profile::SoftPkg>();
  spd->id = name;
  spd->name = name;
  for (const auto &i : impls)
    spd->implementations.push_back(i.impl);
  auto pkg = std::make_shared<profile::ResolvedSoftPkg>();
  pkg->spd_path = name + ".spd.xml";
  pkg->spd = spd;
  for (std::size_t k = 0; k < impls.size(); ++k)
    pkg->implementations.push_back({&spd->implementations[k], nullptr, impls[k].dependencies});
  return pkg;
}

// A GPP with os_name / processor_name matching properties and cpu / mem capacities.
Device gpp(std::string id, std::string node, double cpu = 100, double mem = 1024,
           std::string os = "Linux", std::string processor = "x86_64") {
  Device d;
  d.id = std::move(id);
  d.node = std::move(node);
  d.kind = "gpp";
  d.properties.push_back({"os_name", "os_name", std::move(os), profile::Action::Eq});
  d.properties.push_back(
      {"processor_name", "processor_name", std::move(processor), profile::Action::Eq});
  d.capacity[kCpuCapacity] = cpu;
  d.capacity[kMemCapacity] = mem;
  return d;
}

// A device components use through usesdevice (not a GPP).
Device peripheral(std::string id, std::string node, std::vector<MatchingProperty> properties,
                  std::map<std::string, double> capacity) {
  Device d;
  d.id = std::move(id);
  d.node = std::move(node);
  d.kind = "device";
  d.properties = std::move(properties);
  d.capacity = std::move(capacity);
  return d;
}

DomainState domain(const std::vector<Device> &devices) {
  DomainState state;
  for (const auto &d : devices)
    state[d.id] = DeviceState{d, {}};
  return state;
}

ComponentRequest component(std::string instance, const PkgPtr &pkg) {
  ComponentRequest c;
  c.instance = std::move(instance);
  c.softpkg = pkg.get();
  return c;
}

ComponentRequest periodic(std::string instance, const PkgPtr &pkg, std::int64_t period_ms,
                          std::int64_t execution_ms) {
  ComponentRequest c = component(std::move(instance), pkg);
  c.timing.emplace();
  c.timing->period = Duration{milliseconds{period_ms}};
  c.timing->execution_time = Duration{milliseconds{execution_ms}};
  return c;
}

profile::UsesDevice uses_device(std::string id, std::vector<profile::PropertyRef> requirements) {
  profile::UsesDevice u;
  u.id = std::move(id);
  u.type = "device";
  u.requirements = std::move(requirements);
  return u;
}

profile::LatencyPath latency_path(std::string id, std::int64_t bound_ms,
                                  std::vector<std::string> components) {
  profile::LatencyPath p;
  p.id = std::move(id);
  p.bound = Duration{milliseconds{bound_ms}};
  p.components = std::move(components);
  return p;
}

PlanRequest request_of(std::vector<ComponentRequest> components) {
  PlanRequest r;
  r.components = std::move(components);
  return r;
}

PlanOptions with(Strategy strategy) {
  PlanOptions o;
  o.strategy = strategy;
  return o;
}

// ---- result helpers -----------------------------------------------------------------------------

std::string why(const PlanResult &result) {
  return result ? std::string("(planned)") : to_string(result.error());
}

Plan require_plan(const PlanResult &result) {
  INFO(why(result));
  REQUIRE(result.has_value());
  return *result;
}

std::vector<Rejection> require_rejection(const PlanResult &result) {
  REQUIRE_FALSE(result.has_value());
  return result.error();
}

const Placement &placement_of(const Plan &plan, const std::string &instance) {
  for (const auto &p : plan.placements)
    if (p.instance == instance)
      return p;
  FAIL("no placement for " << instance);
  throw std::logic_error("unreachable");
}

std::string device_of(const Plan &plan, const std::string &instance) {
  return placement_of(plan, instance).device;
}

std::string implementation_of(const Plan &plan, const std::string &instance) {
  return placement_of(plan, instance).implementation->id;
}

double allocated(const DomainState &state, const std::string &device, const std::string &capacity) {
  const auto &a = state.at(device).load.allocated;
  auto it = a.find(capacity);
  return it == a.end() ? 0.0 : it->second;
}

} // namespace

// 1
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: os and processor select the implementation", "[planner]") {
  const auto state = domain({gpp("n1:GPP", "n1", 100, 1024, "Linux", "x86_64")});

  SECTION("the second implementation is tried when the first does not fit") {
    // arm needs armv7, the device is x86_64: only x86 fits.
    auto pkg =
        softpkg("comp", {ImplSpec("arm").processor("armv7"), ImplSpec("x86").processor("x86_64")});
    const Plan plan = require_plan(make_plan(state, request_of({component("c", pkg)})));
    CHECK(device_of(plan, "c") == "n1:GPP");
    CHECK(implementation_of(plan, "c") == "x86");
  }

  SECTION("os: any of the listed os names matches") {
    // qnx needs QNX (device is Linux); multi lists QNX or Linux, so it fits.
    auto pkg =
        softpkg("comp", {ImplSpec("qnx").os("QNX"), ImplSpec("multi").os("QNX").os("Linux")});
    const Plan plan = require_plan(make_plan(state, request_of({component("c", pkg)})));
    CHECK(implementation_of(plan, "c") == "multi");
  }

  SECTION("no implementation fits: rejected with the mismatch per device and implementation") {
    auto pkg = softpkg("comp", {ImplSpec("arm").processor("armv7"), ImplSpec("qnx").os("QNX")});
    const auto rejections = require_rejection(make_plan(state, request_of({component("c", pkg)})));
    REQUIRE(rejections.size() == 1);
    CHECK(rejections[0].instance == "c");
    CHECK(rejections[0].reasons ==
          std::vector<std::string>{
              "n1:GPP (arm): processor_name is x86_64, implementation arm needs armv7",
              "n1:GPP (qnx): os_name is Linux, implementation qnx needs QNX"});
  }
}

// 2
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: matching allocation properties compare device value action required",
          "[planner]") {
  struct Row {
    profile::Action action;
    const char *device_value;
    const char *required;
    bool satisfied; // device_value <action> required, the device's value on the left
  };
  using A = profile::Action;
  const Row rows[] = {
      {A::Eq, "8", "8", true},       // 8 == 8
      {A::Eq, "8", "4", false},      // 8 == 4 false
      {A::Ne, "8", "4", true},       // 8 != 4
      {A::Ne, "8", "8", false},      // 8 != 8 false
      {A::Gt, "8", "4", true},       // 8 > 4
      {A::Gt, "4", "8", false},      // 4 > 8 false (the required value is on the right)
      {A::Gt, "8", "8", false},      // 8 > 8 false
      {A::Gt, "10", "9", true},      // numbers compare as numbers: 10 > 9 (as text "10" < "9")
      {A::Lt, "4", "8", true},       // 4 < 8
      {A::Lt, "8", "4", false},      // 8 < 4 false
      {A::Ge, "8", "8", true},       // 8 >= 8
      {A::Ge, "4", "8", false},      // 4 >= 8 false
      {A::Le, "8", "8", true},       // 8 <= 8
      {A::Le, "8", "4", false},      // 8 <= 4 false
      {A::Eq, "ros2", "ros2", true}, // text equality
      {A::Ne, "ros2", "dds", true},  // text inequality
  };
  SECTION("every action, the device's value on the left") {
    for (const auto &row : rows) {
      INFO("device " << row.device_value << " " << profile::to_string(row.action) << " required "
                     << row.required);
      Device d = gpp("n1:GPP", "n1");
      d.properties.push_back({"DCE:bogomips", "bogomips", row.device_value, row.action});
      // The requirement names the property by id; name lookup is covered by the next check.
      auto pkg = softpkg("comp", {ImplSpec("cpp").needs("DCE:bogomips", row.required)});
      const auto result = make_plan(domain({d}), request_of({component("c", pkg)}));
      CHECK(result.has_value() == row.satisfied);
    }
  }

  SECTION("the reason names the property, its value, the action and the requirement") {
    Device d = gpp("n1:GPP", "n1");
    d.properties.push_back({"DCE:bogomips", "bogomips", "4", profile::Action::Gt});
    auto pkg = softpkg("comp", {ImplSpec("cpp").needs("bogomips", "8")}); // by name: 4 > 8 false
    const auto rejections =
        require_rejection(make_plan(domain({d}), request_of({component("c", pkg)})));
    REQUIRE(rejections.size() == 1);
    CHECK(
        rejections[0].reasons ==
        std::vector<std::string>{
            "n1:GPP (cpp): implementation cpp depends on a device that bogomips is 4, needs gt 8"});
  }

  SECTION("a device without the property does not match") {
    auto pkg = softpkg("comp", {ImplSpec("cpp").needs("gpu_model", "orin")});
    const auto rejections = require_rejection(
        make_plan(domain({gpp("n1:GPP", "n1")}), request_of({component("c", pkg)})));
    CHECK_THAT(to_string(rejections), Catch::Contains("has no allocation property gpu_model"));
  }
}

// 3
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: softpkg dependencies must load on the component's device", "[planner]") {
  // n1 runs QNX, n2 Linux; the component itself runs anywhere.
  const auto state = domain({gpp("n1:GPP", "n1", 100, 1024, "QNX"), gpp("n2:GPP", "n2")});

  SECTION("a dependency whose only implementation needs Linux takes the component to n2") {
    auto lib = softpkg("libdsp", {ImplSpec("dsp_linux").os("Linux")});
    auto pkg = softpkg("comp", {ImplSpec("cpp").depends_on(lib)});
    // Pack would take n1:GPP first (equal load, first id); the dependency rules it out.
    const Plan plan = require_plan(make_plan(state, request_of({component("c", pkg)})));
    CHECK(device_of(plan, "c") == "n2:GPP");
  }

  SECTION("dependencies are matched recursively") {
    // comp -> libdsp (any os) -> libmath (QNX only): only n1 can load the whole chain.
    auto math = softpkg("libmath", {ImplSpec("math_qnx").os("QNX")});
    auto dsp = softpkg("libdsp", {ImplSpec("dsp").depends_on(math)});
    auto pkg = softpkg("comp", {ImplSpec("cpp").depends_on(dsp)});
    const Plan plan = require_plan(make_plan(state, request_of({component("c", pkg)})));
    CHECK(device_of(plan, "c") == "n1:GPP");

    // Without the QNX node nothing can host it, and the reason follows the chain.
    const auto rejections = require_rejection(
        make_plan(domain({gpp("n2:GPP", "n2")}), request_of({component("c", pkg)})));
    CHECK(
        rejections[0].reasons ==
        std::vector<std::string>{"n2:GPP (cpp): dependency libdsp: dependency libmath: os_name is "
                                 "Linux, implementation math_qnx needs QNX"});
  }

  SECTION("an implref restricts the dependency to that implementation") {
    auto lib =
        softpkg("libdsp", {ImplSpec("dsp_qnx").os("QNX"), ImplSpec("dsp_linux").os("Linux")});
    const auto linux_only = domain({gpp("n2:GPP", "n2")});
    auto any = softpkg("comp", {ImplSpec("cpp").depends_on(lib)});
    CHECK(make_plan(linux_only, request_of({component("c", any)})).has_value());
    auto pinned = softpkg("comp", {ImplSpec("cpp").depends_on(lib, "dsp_qnx")});
    CHECK_FALSE(make_plan(linux_only, request_of({component("c", pinned)})).has_value());
  }

  SECTION("the component's second implementation is tried when the first's dependency fails") {
    auto qnx_lib = softpkg("libq", {ImplSpec("q").os("QNX")});
    auto pkg = softpkg("comp", {ImplSpec("with_q").depends_on(qnx_lib), ImplSpec("plain")});
    const Plan plan =
        require_plan(make_plan(domain({gpp("n2:GPP", "n2")}), request_of({component("c", pkg)})));
    CHECK(implementation_of(plan, "c") == "plain");
  }
}

// 4
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: capacities are subtracted per component", "[planner]") {
  const auto state = domain({gpp("n1:GPP", "n1", 100, 1024)});

  SECTION("demands add up on the device") {
    auto a = softpkg("a", {ImplSpec("cpp").utilization(0.6).memory_mib(512)});
    auto b = softpkg("b", {ImplSpec("cpp").utilization(0.3).memory_mib(256)});
    const Plan plan =
        require_plan(make_plan(state, request_of({component("a", a), component("b", b)})));
    // a demands 0.6 * 100 = 60 % CPU and 512 MiB; b 30 % and 256 MiB.
    CHECK(placement_of(plan, "a").demand.at(kCpuCapacity) == Approx(60));
    CHECK(placement_of(plan, "a").demand.at(kMemCapacity) == 512);
    DomainState committed = state;
    commit(committed, plan);
    CHECK(allocated(committed, "n1:GPP", kCpuCapacity) == Approx(90)); // 60 + 30
    CHECK(allocated(committed, "n1:GPP", kMemCapacity) == 768);        // 512 + 256
  }

  SECTION("an application whose sum does not fit is rejected, naming the device") {
    // a takes 60 %, leaving 40 %; b needs 50 %.
    auto a = softpkg("a", {ImplSpec("cpp").utilization(0.6)});
    auto b = softpkg("b", {ImplSpec("cpp").utilization(0.5)});
    const auto rejections =
        require_rejection(make_plan(state, request_of({component("a", a), component("b", b)})));
    REQUIRE(rejections.size() == 1);
    CHECK(rejections[0].instance == "b");
    CHECK(rejections[0].reasons ==
          std::vector<std::string>{"n1:GPP (cpp): cpu_capacity needs 50.0% CPU, 40.0% CPU free"});
  }

  SECTION("memory: 768 + 512 MiB exceed 1024 MiB") {
    auto a = softpkg("a", {ImplSpec("cpp").memory_mib(768)});
    auto b = softpkg("b", {ImplSpec("cpp").memory_mib(512)});
    const auto rejections =
        require_rejection(make_plan(state, request_of({component("a", a), component("b", b)})));
    CHECK_THAT(to_string(rejections),
               Catch::Contains("n1:GPP (cpp): mem_capacity needs 512 MiB, 256 MiB free"));
  }

  SECTION("exactly full fits") {
    // 10 + 20 + 70 = 100 % and 256 + 256 + 512 = 1024 MiB. In doubles 0.7 * 100 is
    // 70.00000000000001, so the float sum exceeds 100 by about 1e-14: the planner must not
    // reject that.
    auto c1 = softpkg("c1", {ImplSpec("cpp").utilization(0.1).memory_mib(256)});
    auto c2 = softpkg("c2", {ImplSpec("cpp").utilization(0.2).memory_mib(256)});
    auto c3 = softpkg("c3", {ImplSpec("cpp").utilization(0.7).memory_mib(512)});
    PlanRequest full = request_of({component("c1", c1), component("c2", c2), component("c3", c3)});
    const Plan plan = require_plan(make_plan(state, full));
    DomainState committed = state;
    commit(committed, plan);
    CHECK(allocated(committed, "n1:GPP", kCpuCapacity) == Approx(100));
    CHECK(allocated(committed, "n1:GPP", kMemCapacity) == 1024);

    // One MiB more does not.
    auto c4 = softpkg("c4", {ImplSpec("cpp").memory_mib(1)});
    full.components.push_back(component("c4", c4));
    const auto rejections = require_rejection(make_plan(state, full));
    CHECK_THAT(to_string(rejections), Catch::Contains("mem_capacity needs 1 MiB, 0 MiB free"));
  }

  SECTION("what is already allocated counts") {
    DomainState loaded = state;
    loaded["n1:GPP"].load.allocated[kCpuCapacity] = 70; // 30 % free
    auto a = softpkg("a", {ImplSpec("cpp").utilization(0.4)});
    const auto rejections = require_rejection(make_plan(loaded, request_of({component("a", a)})));
    CHECK(rejections[0].reasons ==
          std::vector<std::string>{"n1:GPP (cpp): cpu_capacity needs 40.0% CPU, 30.0% CPU free"});
  }

  SECTION("a device without the capacity cannot take the demand") {
    Device d = gpp("n1:GPP", "n1");
    d.capacity.erase(kMemCapacity);
    auto a = softpkg("a", {ImplSpec("cpp").memory_mib(1)});
    const auto rejections =
        require_rejection(make_plan(domain({d}), request_of({component("a", a)})));
    CHECK_THAT(to_string(rejections), Catch::Contains("the device has no mem_capacity capacity"));
  }

  SECTION("an unknown (infinite) capacity is not checked, and the plan says so") {
    const auto unknown =
        domain({gpp("n1:GPP", "n1", 100, std::numeric_limits<double>::infinity())});
    auto a = softpkg("a", {ImplSpec("cpp").memory_mib(1u << 20)}); // 1 TiB
    const Plan plan = require_plan(make_plan(unknown, request_of({component("a", a)})));
    CHECK(plan.notes ==
          std::vector<std::string>{"mem_capacity of n1:GPP is not known: not checked"});
  }
}

// 5
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: host collocation keeps a group on one node", "[planner]") {
  const auto state = domain({gpp("n1:GPP", "n1"), gpp("n2:GPP", "n2")});
  const auto spread = with(Strategy::Spread);

  SECTION("a group lands on one node although spreading would separate it") {
    auto pkg = softpkg("comp", {ImplSpec("cpp").utilization(0.3)});
    PlanRequest request = request_of({component("a", pkg), component("b", pkg)});
    // Without the group: a on n1 (equal load, first id), b on n2 (0 % < 30 %).
    const Plan apart = require_plan(make_plan(state, request, spread));
    CHECK(device_of(apart, "a") == "n1:GPP");
    CHECK(device_of(apart, "b") == "n2:GPP");
    // With it: b follows a to n1 (30 + 30 = 60 % fits).
    request.components[0].collocation = request.components[1].collocation = "g";
    const Plan together = require_plan(make_plan(state, request, spread));
    CHECK(device_of(together, "a") == "n1:GPP");
    CHECK(device_of(together, "b") == "n1:GPP");
  }

  SECTION("a group that fits on no single node is rejected although its members fit apart") {
    auto pkg = softpkg("comp", {ImplSpec("cpp").utilization(0.6)});
    PlanRequest request = request_of({component("a", pkg), component("b", pkg)});
    CHECK(make_plan(state, request).has_value()); // 60 % on each node
    request.components[0].collocation = request.components[1].collocation = "g";
    // 60 + 60 = 120 % > 100 % on either node.
    const auto rejections = require_rejection(make_plan(state, request));
    CHECK_THAT(to_string(rejections), Catch::Contains("hostcollocation g is on node"));
  }

  SECTION("collocation is per node: a node's two GPPs can share a group") {
    const auto two = domain({gpp("n1:GPP_1", "n1"), gpp("n1:GPP_2", "n1"), gpp("n2:GPP", "n2")});
    auto pkg = softpkg("comp", {ImplSpec("cpp").utilization(0.6)});
    PlanRequest request =
        request_of({component("a", pkg), component("b", pkg), component("free", pkg)});
    request.components[0].collocation = request.components[1].collocation = "g";
    const Plan plan = require_plan(make_plan(two, request));
    // a and b need 60 % each: one per GPP of n1; "free" is not in the group and takes n2.
    CHECK(placement_of(plan, "a").node == "n1");
    CHECK(placement_of(plan, "b").node == "n1");
    CHECK(device_of(plan, "a") != device_of(plan, "b"));
    CHECK(device_of(plan, "free") == "n2:GPP");
  }
}

// 6
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: devicerequires and deployerrequires", "[planner]") {
  // n2:GPP offers (deployerrequires) safety=asil-b; n1:GPP offers nothing. Equal load, so pack
  // would take n1:GPP first for anything.
  Device offering = gpp("n2:GPP", "n2");
  offering.deployer_requires["safety"] = "asil-b";
  const auto state = domain({gpp("n1:GPP", "n1"), offering});
  auto pkg = softpkg("comp", {ImplSpec("cpp")});

  SECTION("a component that requires goes only to the device that offers") {
    ComponentRequest c = component("c", pkg);
    c.device_requires.push_back(ref("safety", "asil-b"));
    const Plan plan = require_plan(make_plan(state, request_of({c})));
    CHECK(device_of(plan, "c") == "n2:GPP");

    const auto rejections =
        require_rejection(make_plan(domain({gpp("n1:GPP", "n1")}), request_of({c})));
    CHECK(rejections[0].reasons ==
          std::vector<std::string>{"n1:GPP (cpp): devicerequires safety=asil-b, the device's "
                                   "deployerrequires do not offer it"});

    c.device_requires[0] = ref("safety", "asil-d"); // offered nowhere
    CHECK_FALSE(make_plan(state, request_of({c})).has_value());
  }

  SECTION("a device that offers refuses a component that does not require it") {
    const Plan plan = require_plan(make_plan(state, request_of({component("c", pkg)})));
    CHECK(device_of(plan, "c") == "n1:GPP");

    const auto rejections =
        require_rejection(make_plan(domain({offering}), request_of({component("c", pkg)})));
    CHECK(rejections[0].reasons ==
          std::vector<std::string>{"n2:GPP (cpp): deployerrequires safety=asil-b: the device takes "
                                   "only components that require it"});
  }
}

// 7
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: explicit assignment", "[planner]") {
  const auto state = domain({gpp("n1:GPP", "n1"), gpp("n2:GPP", "n2", 100, 1024, "QNX")});
  auto pkg = softpkg("comp", {ImplSpec("cpp")});
  ComponentRequest c = component("c", pkg);

  SECTION("honoured over the strategy's preference") {
    c.device = "n2:GPP"; // pack would take n1:GPP (equal load, first id)
    const Plan plan = require_plan(make_plan(state, request_of({c})));
    CHECK(device_of(plan, "c") == "n2:GPP");
  }

  SECTION("an unknown device is rejected") {
    c.device = "n9:GPP";
    const auto rejections = require_rejection(make_plan(state, request_of({c})));
    REQUIRE(rejections.size() == 1);
    CHECK(rejections[0].instance == "c");
    CHECK(rejections[0].reasons ==
          std::vector<std::string>{"the assigned device n9:GPP is not in the domain"});
  }

  SECTION("an assigned device that cannot run it is rejected, though another could") {
    auto linux_only = softpkg("comp", {ImplSpec("cpp").os("Linux")});
    ComponentRequest l = component("c", linux_only);
    l.device = "n2:GPP";
    const auto rejections = require_rejection(make_plan(state, request_of({l})));
    CHECK(rejections[0].reasons ==
          std::vector<std::string>{"n2:GPP (cpp): os_name is QNX, implementation cpp needs Linux"});
  }
}

// 8
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: usesdevice places on the used device's node and allocates it", "[planner]") {
  // n2 has a camera with one channel; n1 has none.
  const Device camera = peripheral(
      "n2:camera", "n2", {{"model", "model", "imx219", profile::Action::Eq}}, {{"channels", 1.0}});
  const auto state = domain({gpp("n1:GPP", "n1"), gpp("n2:GPP", "n2"), camera});
  const auto cam = uses_device("cam", {ref("model", "imx219"), ref("channels", "1")});
  auto pkg = softpkg("comp", {ImplSpec("cpp").uses(cam)});

  SECTION("placed on the GPP of the camera's node, the channel reserved") {
    const Plan plan = require_plan(make_plan(state, request_of({component("c", pkg)})));
    const Placement &p = placement_of(plan, "c");
    CHECK(p.device == "n2:GPP"); // n1 has no device with model imx219
    REQUIRE(p.used_devices.size() == 1);
    CHECK(p.used_devices[0].uses_id == "cam");
    CHECK(p.used_devices[0].device == "n2:camera");
    CHECK(p.used_devices[0].demand == std::map<std::string, double>{{"channels", 1.0}});
    DomainState committed = state;
    commit(committed, plan);
    CHECK(allocated(committed, "n2:camera", "channels") == 1);
    // The channel is taken: the same component again does not fit.
    CHECK_FALSE(make_plan(committed, request_of({component("c", pkg)})).has_value());
  }

  SECTION("a second component needing the single channel is rejected") {
    const auto rejections = require_rejection(
        make_plan(state, request_of({component("c1", pkg), component("c2", pkg)})));
    CHECK(rejections[0].instance == "c2");
    CHECK_THAT(to_string(rejections),
               Catch::Contains("usesdevice cam: no device in the domain fits"));
  }

  SECTION("a device on a node without a GPP is used across the network") {
    const Device sensor = peripheral("robot:sensor", "robot",
                                     {{"model", "model", "imx219", profile::Action::Eq}}, {});
    const auto remote = domain({gpp("n1:GPP", "n1"), sensor});
    const Plan plan = require_plan(make_plan(
        remote,
        request_of({component("c", softpkg("comp", {ImplSpec("cpp").uses(uses_device(
                                                       "cam", {ref("model", "imx219")}))}))})));
    const Placement &p = placement_of(plan, "c");
    CHECK(p.device == "n1:GPP");
    REQUIRE(p.used_devices.size() == 1);
    CHECK(p.used_devices[0].device == "robot:sensor");
  }

  SECTION("two usesdevice of one implementation cannot both take the single channel") {
    // 1 + 1 = 2 channels wanted of a camera that has 1: accepting would over-commit it.
    auto twice = softpkg("stereo", {ImplSpec("cpp")
                                        .uses(uses_device("left", {ref("channels", "1")}))
                                        .uses(uses_device("right", {ref("channels", "1")}))});
    const auto result = make_plan(state, request_of({component("s", twice)}));
    if (result) {
      DomainState committed = state;
      commit(committed, *result);
      INFO("camera channels allocated: " << allocated(committed, "n2:camera", "channels"));
      CHECK(allocated(committed, "n2:camera", "channels") <= 1.0);
    }
    CHECK_FALSE(result.has_value());
  }

  SECTION("the application's own usesdevice is reserved in application_devices") {
    auto plain = softpkg("plain", {ImplSpec("cpp")});
    PlanRequest request = request_of({component("c", plain)});
    request.uses_devices.push_back(cam);
    const Plan plan = require_plan(make_plan(state, request));
    REQUIRE(plan.application_devices.size() == 1);
    CHECK(plan.application_devices[0].device == "n2:camera");
    CHECK(plan.application_devices[0].demand == std::map<std::string, double>{{"channels", 1.0}});
  }

  SECTION("a failed application usesdevice does not leak what an earlier one reserved") {
    // n1: GPP + radio (band s, 1 slot); n2: GPP + radio (band x, 1 slot) + the camera.
    // Component c uses any radio slot on its node. The application uses the camera channel
    // ("cam") and a band-s radio slot ("uplink", only n1:radio has band s).
    // The one plan: c on n2:GPP with n2:radio; cam -> n2:camera, uplink -> n1:radio.
    // The search first tries c on n1:GPP (pack, equal load, first id), which takes n1:radio's
    // slot: cam is then reserved, uplink fails. Backtracking to n2:GPP must find the camera free.
    const Device radio1 = peripheral("n1:radio", "n1", {{"band", "band", "s", profile::Action::Eq}},
                                     {{"slots", 1.0}});
    const Device radio2 = peripheral("n2:radio", "n2", {{"band", "band", "x", profile::Action::Eq}},
                                     {{"slots", 1.0}});
    const auto radios = domain({gpp("n1:GPP", "n1"), radio1, gpp("n2:GPP", "n2"), radio2, camera});
    auto linked =
        softpkg("linked", {ImplSpec("cpp").uses(uses_device("link", {ref("slots", "1")}))});
    PlanRequest request = request_of({component("c", linked)});
    request.uses_devices = {cam, uses_device("uplink", {ref("band", "s"), ref("slots", "1")})};
    // The plan exists: pinned to n2:GPP (so the search never tries n1), it is found.
    PlanRequest pinned = request;
    pinned.components[0].device = "n2:GPP";
    CHECK(make_plan(radios, pinned).has_value());
    const Plan plan = require_plan(make_plan(radios, request));
    CHECK(device_of(plan, "c") == "n2:GPP");
    REQUIRE(plan.application_devices.size() == 2);
    CHECK(plan.application_devices[0].device == "n2:camera");
    CHECK(plan.application_devices[1].device == "n1:radio");
  }
}

// 9
// ------------------------------------------------------------------------------------------------
TEST_CASE("planner: timing admission per CPU", "[planner]") {
  auto pkg = softpkg("comp", {ImplSpec("cpp")});
  // a (C=2,T=5), b (C=2,T=7), c (C=2,T=7): U = 0.4 + 0.286 + 0.286 = 0.971 <= 1 and the CPU
  // demand 40 + 28.6 + 28.6 = 97.1 % fits 100 %, so only the response-time analysis decides.
  // Deadline monotonic: a highest, then b, then c (same D and T as b, later in input order).
  //   R_a = 2; R_b = 2 + 2 = 4 <= 7;
  //   R_c: w = 2 + 2 + 2 = 6, w = 2 + ceil(6/5)*2 + ceil(6/7)*2 = 8 > 7: misses.
  const PlanRequest three =
      request_of({periodic("a", pkg, 5, 2), periodic("b", pkg, 7, 2), periodic("c", pkg, 7, 2)});

  SECTION("fixed priority, one CPU: the third task breaks RTA and is rejected") {
    const auto state = domain({gpp("n1:GPP", "n1")});
    CHECK(make_plan(state, request_of({three.components[0], three.components[1]})).has_value());
    const auto rejections = require_rejection(make_plan(state, three));
    REQUIRE(rejections.size() == 1);
    CHECK(rejections[0].instance == "c");
    CHECK_THAT(to_string(rejections), Catch::Contains("timing admission failed on every CPU") &&
                                          Catch::Contains("task c") &&
                                          Catch::Contains("exceeds its deadline 7ms"));
  }

  SECTION("two CPUs: the third task goes to the second CPU, with its schedule") {
    Device d = gpp("n1:GPP", "n1", 200);
    d.cpus = 2;
    const Plan plan = require_plan(make_plan(domain({d}), three));
    // Pack fills the most loaded CPU first: a and b on CPU 0, c does not fit there -> CPU 1.
    const auto &sa = placement_of(plan, "a").schedule;
    const auto &sb = placement_of(plan, "b").schedule;
    const auto &sc = placement_of(plan, "c").schedule;
    REQUIRE((sa && sb && sc));
    CHECK(sa->cpu == 0);
    CHECK(sb->cpu == 0);
    // b is the lower of CPU 0's two tasks: priority 1, R_b = 4 ms.
    CHECK(sb->priority == 1);
    CHECK(sb->response_time == milliseconds{4});
    // c alone on CPU 1: priority 1 (the least urgent gets 1), R = C = 2 ms.
    CHECK(sc->cpu == 1);
    CHECK(sc->policy == SchedulingPolicy::FixedPriority);
    CHECK(sc->priority == 1);
    CHECK(sc->period == milliseconds{7});
    CHECK(sc->budget == milliseconds{2});
    CHECK(sc->deadline == milliseconds{7});
    CHECK(sc->response_time == milliseconds{2});
    // The periodic demand is also CPU capacity: 100 * C / T = 40 %.
    CHECK(placement_of(plan, "a").demand.at(kCpuCapacity) == Approx(40));
  }

  SECTION("EDF admits a set fixed priority rejects") {
    // (C=2,T=5), (C=4,T=7): U = 2/5 + 4/7 = 34/35 <= 1 -> EDF schedulable.
    // FP: R_b: w = 4 + 2 = 6, w = 4 + ceil(6/5)*2 = 8 > 7 -> misses.
    const PlanRequest pair = request_of({periodic("a", pkg, 5, 2), periodic("b", pkg, 7, 4)});
    const auto fp = require_rejection(make_plan(domain({gpp("n1:GPP", "n1")}), pair));
    CHECK_THAT(to_string(fp), Catch::Contains("task b"));

    Device edf = gpp("n1:GPP", "n1");
    edf.policy = SchedulingPolicy::Edf;
    const Plan plan = require_plan(make_plan(domain({edf}), pair));
    const auto &sb = placement_of(plan, "b").schedule;
    REQUIRE(sb);
    CHECK(sb->policy == SchedulingPolicy::Edf);
    CHECK(sb->priority == 0);                    // EDF has no priorities
    CHECK(sb->response_time == milliseconds{7}); // EDF guarantees the deadline
    CHECK(sb->budget == milliseconds{4});
  }

  SECTION("an earlier component's schedule reflects later admissions on its CPU") {
    // x (C=1,T=4) is placed first, alone: priority 1. Then y (C=10,T=100) joins the CPU and
    // the analysis of {x, y} ranks x above y (deadline monotonic): x 2, y 1;
    // R_x = 1, R_y: w = 10 + 1 = 11 -> 10 + ceil(11/4)*1 = 13 -> 10 + 4 = 14 -> 14 <= 100.
    // x must be delivered priority 2: at priority 1 it ties with y and can wait for y's 10 ms
    // (R_x = 1 + 10 = 11 > 4), a deadline miss the admission never checked.
    const auto state = domain({gpp("n1:GPP", "n1")});
    const Plan plan = require_plan(
        make_plan(state, request_of({periodic("x", pkg, 4, 1), periodic("y", pkg, 100, 10)})));
    const auto &sx = placement_of(plan, "x").schedule;
    const auto &sy = placement_of(plan, "y").schedule;
    REQUIRE((sx && sy));
    CHECK(sx->priority > sy->priority);
    CHECK(sy->response_time == milliseconds{14});
    // What is committed is what gets deployed: it must pass the same analysis.
    DomainState committed = state;
    commit(committed, plan);
    const auto verdict =
        analyse(committed.at("n1:GPP").load.cpu_tasks.at(0), SchedulingPolicy::FixedPriority);
    INFO(verdict.reason);
    CHECK(verdict.schedulable);
  }
}

// 10
// -----------------------------------------------------------------------------------------------
TEST_CASE("planner: end-to-end latency paths", "[planner]") {
  auto pkg = softpkg("comp", {ImplSpec("cpp")});
  const auto state = domain({gpp("n1:GPP", "n1")});
  // One CPU, a (C=2,T=10) above b (C=3,T=20): R_a = 2; R_b: w = 3 + 2 = 5 -> 3 + ceil(5/10)*2 = 5.
  // Path a -> b: R_a + (T_b + R_b) = 2 + 20 + 5 = 27 ms.
  PlanRequest request = request_of({periodic("a", pkg, 10, 2), periodic("b", pkg, 20, 3)});

  SECTION("a bound equal to the worst case is met") {
    request.latency_paths.push_back(latency_path("p", 27, {"a", "b"}));
    const Plan plan = require_plan(make_plan(state, request));
    CHECK(placement_of(plan, "b").schedule->response_time == milliseconds{5});
  }

  SECTION("a bound below the worst case rejects the application, naming the path") {
    request.latency_paths.push_back(latency_path("p", 26, {"a", "b"}));
    const auto rejections = require_rejection(make_plan(state, request));
    REQUIRE(rejections.size() == 1);
    CHECK(rejections[0].instance == "(application)");
    CHECK(rejections[0].reasons ==
          std::vector<std::string>{"latency path p: worst case 27ms exceeds its bound 26ms"});
  }

  SECTION("the worst case uses response times of the final task set") {
    // b is listed (and placed) first: alone its response is 3 ms. Then a joins the CPU above
    // it, and R_b becomes 5 ms. Path b -> a: R_b + (T_a + R_a) = 5 + 10 + 2 = 17 ms > 16 ms.
    // (With the stale R_b = 3 it would be 15 ms and wrongly accepted.)
    PlanRequest reversed = request_of({request.components[1], request.components[0]});
    reversed.latency_paths.push_back(latency_path("q", 16, {"b", "a"}));
    const auto result = make_plan(state, reversed);
    if (result)
      CHECK(placement_of(*result, "b").schedule->response_time == milliseconds{5});
    CHECK_FALSE(result.has_value());
  }
}

// 11
// -----------------------------------------------------------------------------------------------
TEST_CASE("planner: strategies, affinity and determinism", "[planner]") {
  const auto state = domain({gpp("n1:GPP", "n1"), gpp("n2:GPP", "n2")});
  auto pkg = softpkg("comp", {ImplSpec("cpp").utilization(0.3)});
  PlanRequest pair = request_of({component("a", pkg), component("b", pkg)});

  SECTION("pack puts two components on one device, spread on two") {
    // Pack: a on n1 (equal load, first id), then b on the most loaded device that fits: n1.
    const Plan packed = require_plan(make_plan(state, pair, with(Strategy::Pack)));
    CHECK(device_of(packed, "a") == "n1:GPP");
    CHECK(device_of(packed, "b") == "n1:GPP");
    // Spread: b on the least loaded: n2 (0 % < 30 %).
    const Plan spread = require_plan(make_plan(state, pair, with(Strategy::Spread)));
    CHECK(device_of(spread, "a") == "n1:GPP");
    CHECK(device_of(spread, "b") == "n2:GPP");
  }

  SECTION("pack: a connected pair stays on one node") {
    // n2 already carries 50 %; a is assigned to n1. Pack alone sends b to the fuller n2
    // (50 % > 30 %); the affinity a-b keeps it with a on n1.
    DomainState loaded = state;
    loaded["n2:GPP"].load.allocated[kCpuCapacity] = 50;
    pair.components[0].device = "n1:GPP";
    CHECK(device_of(require_plan(make_plan(loaded, pair)), "b") == "n2:GPP");
    pair.affinities.push_back({"a", "b", 1.0});
    CHECK(device_of(require_plan(make_plan(loaded, pair)), "b") == "n1:GPP");
  }

  SECTION("spread: a heavy pair (weight >= 10) stays together, a light one is spread") {
    const auto spread = with(Strategy::Spread);
    pair.affinities.push_back({"a", "b", 1.0});
    CHECK(device_of(require_plan(make_plan(state, pair, spread)), "b") == "n2:GPP");
    pair.affinities[0].weight = 10.0;
    CHECK(device_of(require_plan(make_plan(state, pair, spread)), "b") == "n1:GPP");
  }

  SECTION("spread: a chain lands as runs of neighbours, a fair share per device") {
    // Six in a chain on three devices: two each, neighbours together (2 connections cross
    // devices, not 5 as alternating would give).
    const auto three = domain({gpp("n1:GPP", "n1"), gpp("n2:GPP", "n2"), gpp("n3:GPP", "n3")});
    auto light = softpkg("light", {ImplSpec("cpp").utilization(0.01)});
    std::vector<ComponentRequest> chain;
    for (const char *id : {"c1", "c2", "c3", "c4", "c5", "c6"})
      chain.push_back(component(id, light));
    PlanRequest request = request_of(chain);
    for (std::size_t k = 1; k < chain.size(); ++k)
      request.affinities.push_back({chain[k - 1].instance, chain[k].instance, 1.0});
    const Plan plan = require_plan(make_plan(three, request, with(Strategy::Spread)));
    CHECK(device_of(plan, "c1") == device_of(plan, "c2"));
    CHECK(device_of(plan, "c3") == device_of(plan, "c4"));
    CHECK(device_of(plan, "c5") == device_of(plan, "c6"));
    const std::set<std::string> used{device_of(plan, "c1"), device_of(plan, "c3"),
                                     device_of(plan, "c5")};
    CHECK(used.size() == 3);
  }

  SECTION("the same input gives the same plan") {
    auto other = softpkg("other", {ImplSpec("qnx").os("QNX"), ImplSpec("linux").utilization(0.2)});
    PlanRequest request =
        request_of({component("a", pkg), component("b", other), periodic("p", pkg, 10, 1),
                    component("c", pkg), component("d", other)});
    request.components[0].collocation = request.components[3].collocation = "g";
    request.affinities.push_back({"b", "d", 3.0});
    for (const auto strategy : {Strategy::Pack, Strategy::Spread}) {
      const Plan first = require_plan(make_plan(state, request, with(strategy)));
      const Plan second = require_plan(make_plan(DomainState(state), request, with(strategy)));
      REQUIRE(first.placements.size() == second.placements.size());
      for (std::size_t k = 0; k < first.placements.size(); ++k) {
        const auto &x = first.placements[k];
        const auto &y = second.placements[k];
        CHECK(x.instance == y.instance);
        CHECK(x.device == y.device);
        CHECK(x.implementation == y.implementation);
        CHECK(x.demand == y.demand);
        CHECK(x.schedule.has_value() == y.schedule.has_value());
        if (x.schedule && y.schedule) {
          CHECK(x.schedule->cpu == y.schedule->cpu);
          CHECK(x.schedule->priority == y.schedule->priority);
          CHECK(x.schedule->response_time == y.schedule->response_time);
        }
      }
    }
  }
}

// 12
// -----------------------------------------------------------------------------------------------
TEST_CASE("planner: ResourceAllocator commits whole plans and gives everything back", "[planner]") {
  ResourceAllocator allocator;
  allocator.set_node_devices("n1", {gpp("n1:GPP", "n1")});
  allocator.set_node_devices("n2", {gpp("n2:GPP", "n2")});
  const DomainState empty = allocator.snapshot();

  // app1: a (60 %, 512 MiB) and p (C=1,T=10: 10 %). Pack: a on n1 (first id), p follows to n1.
  auto big = softpkg("big", {ImplSpec("cpp").utilization(0.6).memory_mib(512)});
  auto tiny = softpkg("tiny", {ImplSpec("cpp")});
  const PlanRequest app1 = request_of({component("a", big), periodic("p", tiny, 10, 1)});

  const auto planned = allocator.plan(app1, {});
  REQUIRE(planned.has_value());
  CHECK(rsca::test::same_load(allocator.snapshot(), empty)); // plan() reserves nothing

  const auto first = allocator.allocate(app1, {});
  REQUIRE(first.has_value());
  const DomainState after_first = allocator.snapshot();
  CHECK(allocated(after_first, "n1:GPP", kCpuCapacity) == Approx(70)); // 60 + 10
  CHECK(allocated(after_first, "n1:GPP", kMemCapacity) == 512);
  REQUIRE(after_first.at("n1:GPP").load.cpu_tasks.size() == 1);
  REQUIRE(after_first.at("n1:GPP").load.cpu_tasks[0].size() == 1);
  CHECK(after_first.at("n1:GPP").load.cpu_tasks[0][0].id == "p");

  SECTION("a rejected allocation leaves the state unchanged") {
    // x and y (60 % each) in one group: n1 has 30 % free, n2 100 %: no node takes 120 %.
    PlanRequest app2 = request_of({component("x", big), component("y", big)});
    app2.components[0].collocation = app2.components[1].collocation = "g";
    CHECK_FALSE(allocator.allocate(app2, {}).has_value());
    CHECK(rsca::test::same_load(allocator.snapshot(), after_first));
  }

  SECTION("release gives everything back") {
    allocator.release(*first);
    const DomainState released = allocator.snapshot();
    for (const auto &[id, s] : released) {
      for (const auto &[name, amount] : s.load.allocated)
        CHECK(amount == Approx(0).margin(1e-9));
      for (const auto &tasks : s.load.cpu_tasks)
        CHECK(tasks.empty());
    }
  }

  SECTION("set_node_devices keeps the load of devices that remain") {
    Device bigger = gpp("n1:GPP", "n1", 200, 2048);
    allocator.set_node_devices("n1", {bigger, gpp("n1:GPP_2", "n1")});
    const DomainState s = allocator.snapshot();
    REQUIRE(s.size() == 3);
    CHECK(s.at("n1:GPP").device.capacity.at(kCpuCapacity) == 200); // the new description
    CHECK(s.at("n1:GPP").load.allocated == after_first.at("n1:GPP").load.allocated);
    CHECK((s.at("n1:GPP").load.cpu_tasks == after_first.at("n1:GPP").load.cpu_tasks));
    CHECK(s.at("n1:GPP_2").load.allocated.empty());
    CHECK(s.at("n2:GPP").load.allocated == after_first.at("n2:GPP").load.allocated);

    // A device the node no longer announces is gone.
    allocator.set_node_devices("n1", {gpp("n1:GPP_2", "n1")});
    CHECK(allocator.snapshot().count("n1:GPP") == 0);
  }

  SECTION("remove_node drops the node's devices and their load") {
    allocator.remove_node("n1");
    const DomainState s = allocator.snapshot();
    REQUIRE(s.size() == 1);
    CHECK(s.count("n2:GPP") == 1);
    allocator.release(*first); // its devices are gone: nothing to give back, nothing breaks
    CHECK(rsca::test::same_load(allocator.snapshot(), s));
  }
}
