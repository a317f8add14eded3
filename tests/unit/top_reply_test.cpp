// node.top's reply as the CLI reads it (protocol/node_ops.hpp): what a node may not say is
// refused by the decoder, not shown.
#include <catch2/catch.hpp>

#include "protocol/node_ops.hpp"

namespace op = rsca::protocol::node;
using rsca::protocol::Json;

namespace {

Json figures(double cpu = 1.5) {
  return {{"pid", 10}, {"cpu_percent", cpu}, {"rss_bytes", 4096}, {"threads", 2}};
}

Json reply(std::size_t processes, double cpu = 1.5) {
  Json list = Json::array();
  for (std::size_t i = 0; i < processes; ++i)
    list.push_back({{"application", "App"}, {"component", "C"}, {"figures", figures(cpu)}});
  return {{"node", "node1"}, {"host", "h"}, {"daemon", figures()}, {"processes", list}};
}

} // namespace

TEST_CASE("a node's top reply within its bounds is read", "[protocol][top]") {
  auto read = rsca::protocol::decode<op::TopReply>(reply(3));
  REQUIRE(read.has_value());
  CHECK(read->processes.size() == 3);
  CHECK(read->processes[1].figures.cpu_percent == Approx(1.5));
}

TEST_CASE("a node's top reply past its bounds is refused with the field", "[protocol][top]") {
  auto too_many = rsca::protocol::decode<op::TopReply>(reply(op::TopReply::kMaxProcesses + 1));
  REQUIRE_FALSE(too_many.has_value());
  CHECK(too_many.error().find("processes") != std::string::npos);
  auto negative = rsca::protocol::decode<op::TopReply>(reply(1, -3.0));
  REQUIRE_FALSE(negative.has_value());
  CHECK(negative.error().find("processes[0].figures.cpu_percent") != std::string::npos);
  auto bad_pid = reply(0);
  bad_pid["daemon"]["pid"] = 0;
  CHECK_FALSE(rsca::protocol::decode<op::TopReply>(bad_pid).has_value());
}
