// A node's announcement as the domain reads it (protocol/node_ops.hpp): the devices it did not
// start travel with the file and the symbol named, within bounds the decoder checks; a node with
// none says nothing of them, so that a domain that does not know the field still takes it.
#include <catch2/catch.hpp>

#include "protocol/domain_ops.hpp"
#include "protocol/node_ops.hpp"

namespace op = rsca::protocol::node;
using rsca::protocol::Json;

namespace {

Json failed_device_json(std::size_t reason_bytes = 20) {
  return {{"id", "partial:NoSymbol_1"},
          {"label", "NoSymbol_1"},
          {"softpkg", "NoSymbol"},
          {"file", "/usr/lib/rsca/libx.so"},
          {"symbol", "rsca_device_factories"},
          {"reason", std::string(reason_bytes, 'r')}};
}

Json announcement_with(std::size_t failed, Json one = failed_device_json()) {
  Json list = Json::array();
  for (std::size_t i = 0; i < failed; ++i)
    list.push_back(one);
  return {{"node", "partial"},
          {"pid", 42},
          {"host", "h"},
          {"devices", Json::array()},
          {"relays_processes", true},
          {"failed_devices", list}};
}

std::string decode_error_of(const Json &announcement) {
  auto read = rsca::protocol::decode<op::NodeAnnouncement>(announcement);
  return read ? std::string() : read.error();
}

} // namespace

TEST_CASE("a node's announcement carries the devices it did not start, file and symbol named",
          "[protocol][devices]") {
  auto read = rsca::protocol::decode<op::NodeAnnouncement>(announcement_with(2));
  REQUIRE(read.has_value());
  REQUIRE(read->failed_devices.has_value());
  REQUIRE(read->failed_devices->size() == 2);
  const auto &failed = read->failed_devices->front();
  CHECK(failed.id == "partial:NoSymbol_1");
  CHECK(failed.file == "/usr/lib/rsca/libx.so");
  CHECK(failed.symbol == "rsca_device_factories");
  // Written back as it was read: the domain passes it on to `rsca ls nodes` unchanged.
  CHECK(rsca::protocol::encode(*read) == announcement_with(2));
}

TEST_CASE("a node's announcement with every device started says nothing of failed devices",
          "[protocol][devices]") {
  op::NodeAnnouncement all_started{"node1", 7, "h", {}, true, {}};
  const Json encoded = rsca::protocol::encode(all_started);
  CHECK_FALSE(encoded.contains("failed_devices"));
  Json earlier = announcement_with(0);
  earlier.erase("failed_devices");
  auto read = rsca::protocol::decode<op::NodeAnnouncement>(earlier);
  REQUIRE(read.has_value());
  CHECK_FALSE(read->failed_devices.has_value());
}

TEST_CASE("a node's failed devices past their bounds are refused with the field",
          "[protocol][devices]") {
  CHECK(decode_error_of(announcement_with(op::NodeAnnouncement::kMaxFailedDevices)).empty());
  CHECK_THAT(decode_error_of(announcement_with(op::NodeAnnouncement::kMaxFailedDevices + 1)),
             Catch::Contains("failed_devices") && Catch::Contains("more than"));
  CHECK(decode_error_of(announcement_with(1, failed_device_json(op::FailedDevice::kMaxReason)))
            .empty());
  CHECK_THAT(
      decode_error_of(announcement_with(1, failed_device_json(op::FailedDevice::kMaxReason + 1))),
      Catch::Contains("failed_devices[0].reason"));
  Json long_file = failed_device_json();
  long_file["file"] = std::string(op::FailedDevice::kMaxPath + 1, 'f');
  CHECK_THAT(decode_error_of(announcement_with(1, long_file)),
             Catch::Contains("failed_devices[0].file"));
  Json long_label = failed_device_json();
  long_label["label"] = std::string(op::FailedDevice::kMaxName + 1, 'l');
  CHECK_THAT(decode_error_of(announcement_with(1, long_label)),
             Catch::Contains("failed_devices[0]") && Catch::Contains("too long"));
  Json no_reason = failed_device_json();
  no_reason.erase("reason");
  CHECK_THAT(decode_error_of(announcement_with(1, no_reason)),
             Catch::Contains("missing field \"reason\""));
}

TEST_CASE("the domain's list of nodes carries a node's failed devices and the nodes it lost",
          "[protocol][devices]") {
  namespace dom = rsca::protocol::domain;
  op::FailedDevice failed{"n:D_1", "D_1", "D", "/lib/libd.so", "rsca_device_factories", "why"};
  dom::NodesReply reply{{{"n", "rsca/node/n", 3, 1, std::vector{failed}}},
                        {},
                        {{"gone", "rsca/node/gone", 4, 2, std::nullopt}}};
  const Json encoded = rsca::protocol::encode(reply);
  auto read = rsca::protocol::decode<dom::NodesReply>(encoded);
  REQUIRE(read.has_value());
  REQUIRE(read->nodes.at(0).failed_devices.has_value());
  CHECK(read->nodes.at(0).failed_devices->at(0).symbol == "rsca_device_factories");
  REQUIRE(read->lost.size() == 1);
  CHECK(read->lost[0].name == "gone");
  CHECK_FALSE(encoded.at("lost").at(0).contains("failed_devices"));
}
