// Devices as libraries (node/device_libraries.hpp), with real daemons: a node whose DCD names
// devices that cannot be loaded starts with the others, and its log says why for each, naming
// the file and the symbol.
#include <algorithm>
#include <fstream>
#include <iterator>

#include "domain_fixture.hpp"

using namespace rsca::test;
using namespace std::chrono_literals;

namespace {

const fs::path kPartialNode = kTestSdr / "dev/nodes/partial/DeviceManager.dcd.xml";

std::string read_file(const fs::path &path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::vector<std::string> device_ids_of(TestDomain &domain, const std::string &node) {
  auto devices = domain.call("domain.devices");
  REQUIRE(devices.has_value());
  std::vector<std::string> ids;
  for (const auto &d : devices->at("devices"))
    if (d.at("id").get<std::string>().rfind(node + ":", 0) == 0)
      ids.push_back(d.at("id").get<std::string>());
  std::sort(ids.begin(), ids.end());
  return ids;
}

} // namespace

TEST_CASE("a node whose devices cannot be loaded starts with the others and says why, naming the "
          "file and the symbol",
          "[integration][devices]") {
  TestDomain domain(1);
  const fs::path log = domain.run_dir() / "partial.log";
  ChildProcess node(
      (kBin / "rsca-noded").string(),
      {"--dcd", kPartialNode.string(), "--log-dir", (domain.run_dir() / "logs").string()},
      domain.env(), log);
  REQUIRE(TestDomain::wait_for([&] {
    auto nodes = domain.call("domain.nodes");
    return nodes && nodes->at("nodes").size() == 2;
  }));
  CHECK(device_ids_of(domain, "partial") ==
        std::vector<std::string>{"partial:GPP_1", "partial:HostMonitor_1"});

  const std::string text = read_file(log);
  INFO(text);
  CHECK_THAT(text, Catch::Contains(
                       "device partial:NoLibrary_1 (NoLibrary) not started: cannot "
                       "load " +
                       (kTestSdr / "dev/devices/NoLibrary/librsca-no-such-device.so").string()));
  CHECK_THAT(text, Catch::Contains("device partial:NoSymbol_1 (NoSymbol) not started:"));
  CHECK_THAT(text, Catch::Contains("librsca_xml_reader.so exports no rsca_device_factories"));

  // The devices loaded run: the host monitor, from its library, answers for its properties.
  auto [rc, out] = domain.cli({"query", "partial:HostMonitor_1"});
  INFO(out);
  CHECK(rc == 0);
  CHECK_THAT(out, Catch::Contains("period_ms"));
}
