// Devices as the allocator sees them: from a node's announcement and, offline, from a DCD.
#include <cmath>
#include <filesystem>

#include <catch2/catch.hpp>

#include "allocator/device.hpp"

using namespace rsca;
using Json = nlohmann::json;

namespace {

const std::filesystem::path kSource = RSCA_SOURCE_DIR;

allocator::Device offline_device(const std::filesystem::path &dcd) {
  profile::ProfileLoader loader;
  auto node = loader.load_node(dcd);
  INFO((node ? std::string() : node.error().to_string()));
  REQUIRE(node.has_value());
  auto devices = allocator::devices_of_node(*node);
  REQUIRE(devices.size() == 1);
  return devices.front();
}

} // namespace

TEST_CASE("a device from a node's announcement keeps the PRF's ids and actions",
          "[allocator][device]") {
  const Json entry = Json::parse(R"({
    "id": "n1:GPP_1", "kind": "gpp",
    "properties": {"os_name": "Linux", "processor_name": "x86_64", "hostname": "robot",
                   "scheduling_policy": "edf"},
    "capacity": {"cpu_capacity": 200.0, "mem_capacity": 1024.0},
    "allocation": [{"id": "DCE:4a23", "name": "os_name", "action": "eq"},
                   {"id": "DCE:fefb", "name": "processor_name", "action": "ne"},
                   {"id": "cpu_capacity", "name": "cpu_capacity", "action": "external"}],
    "deployerrequires": {"site": "front"}})");
  const auto device = allocator::device_from_announcement("n1", entry);
  CHECK(device.id == "n1:GPP_1");
  CHECK(device.node == "n1");
  CHECK(device.kind == "gpp");
  // Found by the PRF id (what SPD propertyrefs name) and by name (what os/processor match).
  const auto *os = device.find_property("DCE:4a23");
  REQUIRE(os != nullptr);
  CHECK(os == device.find_property("os_name"));
  CHECK(os->value == "Linux");
  CHECK(os->action == profile::Action::Eq);
  CHECK(device.find_property("processor_name")->action == profile::Action::Ne);
  // Reported but not an allocation property: matched by eq.
  CHECK(device.property_value("hostname") == "robot");
  CHECK(device.capacity.at("cpu_capacity") == 200.0);
  CHECK(device.find_property("cpu_capacity") == nullptr); // a capacity, not a matching property
  CHECK(device.cpus == 2);                                // 200% of a core
  CHECK(device.policy == allocator::SchedulingPolicy::Edf);
  CHECK(device.deployer_requires == std::map<std::string, std::string>{{"site", "front"}});
}

TEST_CASE("offline, a DCD's devices are valued from their PRFs and the DCD's overrides",
          "[allocator][device]") {
  SECTION("the project's node: PRF defaults, capacities unknown") {
    const auto gpp = offline_device(kSource / "profiles/dev/nodes/node1/DeviceManager.dcd.xml");
    CHECK(gpp.id == "node1:GPP_1");
    CHECK(gpp.kind == "gpp"); // its SCD says executabledevice
    CHECK(gpp.property_value("os_name") == "Linux");
    CHECK(gpp.property_value("DCE:fefb9c66-d14a-438d-ad59-2cfd1adb272b") == "x86_64");
    CHECK(std::isinf(gpp.capacity.at("cpu_capacity"))); // measured on a host; unknown offline
    CHECK(gpp.policy == allocator::SchedulingPolicy::FixedPriority);
    CHECK(gpp.cpus == 1);
  }
  SECTION("a test node whose DCD gives the CPU capacity") {
    const auto gpp =
        offline_device(kSource / "tests/data/integration/dev/nodes/small1/DeviceManager.dcd.xml");
    CHECK(gpp.id == "small1:GPP_1");
    CHECK(gpp.capacity.at("cpu_capacity") == 100.0);
    CHECK(gpp.cpus == 1);
  }
}

TEST_CASE("amounts read as users think of them", "[allocator][device]") {
  CHECK(allocator::describe_amount("mem_capacity", 512) == "512 MiB");
  CHECK(allocator::describe_amount("cpu_capacity", 25) == "25.0% CPU");
  CHECK(allocator::describe_amount("nic_bandwidth", 100) == "100 Mbps");
  CHECK(allocator::describe_amount("channels", 2) == "2");
  CHECK(allocator::describe_amount("cpu_capacity", INFINITY) == "unknown");
}
