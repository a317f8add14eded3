// The ways to other endpoints (control/partition_writers.hpp): one shared way for every CLI
// client, one per other address, and none for an address that is a pattern.
#include <catch2/catch.hpp>

#include "control.h" // generated from dds/control.idl
#include "control/partition_writers.hpp"
#include "test_domain.hpp"
#include "writers_into.hpp"

using namespace rsca;
using rsca::test::writers_into;

TEST_CASE("reply ways: one for all CLI clients, one per other address, none for a pattern",
          "[control]") {
  auto pp = test::participant();
  auto qos = dds::make_qos();
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds::Entity topic(
      dds_create_topic(pp->get(), &rsca_ctl_Reply_desc, "rsca_ctl_Reply", qos.get(), nullptr));
  REQUIRE(topic.get() > 0);
  control::PartitionWriters ways(pp->get(), topic.get(), qos.get());
  auto a = ways.writer_for("test/cli/host-1-1");
  auto b = ways.writer_for("test/cli/host-2-7");
  auto node = ways.writer_for("test/node/node1");
  REQUIRE(a.has_value());
  REQUIRE(b.has_value());
  REQUIRE(node.has_value());
  CHECK(*a == *b);
  CHECK(*a != *node);
  CHECK(ways.size() == 2);
  for (const char *pattern : {"test/cli/*", "test/node/?", "test/[ab]"}) {
    auto refused = ways.writer_for(pattern);
    REQUIRE_FALSE(refused.has_value());
    CHECK(refused.error().status == control::Status::BadRequest);
  }
  CHECK(ways.size() == 2);
  CHECK(writers_into(pp, "rsca_ctl_Reply", "test/cli/*") == 1);
}
