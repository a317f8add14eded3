// Devices as libraries (node/device_libraries.hpp), with real daemons: a node whose DCD names
// devices that cannot be loaded starts with the others, and its log and its announcement say why
// for each, naming the file and the symbol, which `rsca ls nodes` shows.
#include <algorithm>
#include <fstream>
#include <iterator>

#include "domain_fixture.hpp"

using namespace rsca::test;
using namespace std::chrono_literals;

namespace {

const fs::path kPartialNode = kTestSdr / "dev/nodes/partial/DeviceManager.dcd.xml";

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

// What `rsca ls nodes --json` prints.
Json nodes_listed(TestDomain &domain) {
  auto [rc, out] = domain.cli({"ls", "nodes", "--json"});
  INFO(out);
  REQUIRE(rc == 0);
  return Json::parse(out);
}

// Node `node` of what `rsca ls nodes --json` printed; null when it is not there.
Json node_named(const Json &listed, const std::string &node) {
  for (const auto &n : listed.at("nodes"))
    if (n.at("name") == node)
      return n;
  return nullptr;
}

// The failed device `id` of a node as `rsca ls nodes --json` lists it; null when it is not there.
Json failed_device(const Json &node, const std::string &id) {
  for (const auto &f : node.value("failed_devices", Json::array()))
    if (f.at("id") == id)
      return f;
  return nullptr;
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

  // The devices that failed reach users, with the file and the symbol apart; those loaded are
  // announced.
  // Waited for: on a loaded host a node may miss its 1 s lease, and be listed as lost meanwhile.
  Json listed_json;
  TestDomain::wait_for([&] {
    listed_json = nodes_listed(domain);
    return node_named(listed_json, "partial").is_object();
  });
  INFO(listed_json.dump(2));
  const Json partial = node_named(listed_json, "partial");
  REQUIRE(partial.is_object());
  CHECK(partial.at("devices") == 2);
  REQUIRE(partial.at("failed_devices").size() == 2);
  const Json no_library = failed_device(partial, "partial:NoLibrary_1");
  REQUIRE(no_library.is_object());
  CHECK(no_library.at("label") == "NoLibrary_1");
  CHECK(no_library.at("file") ==
        (kTestSdr / "dev/devices/NoLibrary/librsca-no-such-device.so").string());
  CHECK(no_library.value("symbol", "").empty()); // never looked up: the file did not load
  CHECK_THAT(no_library.at("reason").get<std::string>(), Catch::Contains("cannot load"));
  const Json no_symbol = failed_device(partial, "partial:NoSymbol_1");
  REQUIRE(no_symbol.is_object());
  CHECK_THAT(no_symbol.at("file").get<std::string>(), Catch::EndsWith("librsca_xml_reader.so"));
  CHECK(no_symbol.at("symbol") == "rsca_device_factories");
  // A node whose devices all started says nothing of them.
  CHECK_FALSE(node_named(listed_json, "node1").contains("failed_devices"));
  auto [listed_rc, listed] = domain.cli({"ls", "nodes"});
  INFO(listed);
  CHECK(listed_rc == 0);
  CHECK_THAT(listed, Catch::Contains("not started: partial:NoSymbol_1 (NoSymbol): ") &&
                         Catch::Contains("exports no rsca_device_factories"));

  // The devices loaded run: the host monitor, from its library, answers for its properties.
  auto [rc, out] = domain.cli({"query", "partial:HostMonitor_1"});
  INFO(out);
  CHECK(rc == 0);
  CHECK_THAT(out, Catch::Contains("period_ms"));
}
