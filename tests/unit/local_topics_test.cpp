// In-host connections (component/local_topics.hpp): the inbox keeps the reader's history depth,
// a topic hands one shared sample to every reader, and a topic name keeps its port type.
#include <memory>
#include <string>

#include <catch2/catch.hpp>

#include "component/local_topics.hpp"
#include "component/receive_loop.hpp"

using namespace rsca;
using component::detail::LocalInbox;
using component::detail::LocalSample;
using component::detail::LocalTopics;
using component::detail::ReceiveLoop;
using port::PortType;

namespace {

std::unique_ptr<ReceiveLoop> idle_loop() {
  auto loop = ReceiveLoop::start([] {});
  REQUIRE(loop.has_value());
  return std::move(*loop);
}

LocalSample sample(int value) {
  return std::make_shared<const int>(value);
}

int value_of(const LocalSample &s) {
  return *static_cast<const int *>(s.get());
}

} // namespace

TEST_CASE("an in-host inbox keeps the last `depth` samples, or all with depth 0", "[component]") {
  auto loop = idle_loop();
  LocalInbox keep_last(*loop, 2);
  for (int i = 1; i <= 5; ++i)
    keep_last.push(sample(i));
  auto taken = keep_last.take();
  REQUIRE(taken.size() == 2);
  CHECK(value_of(taken[0]) == 4);
  CHECK(value_of(taken[1]) == 5);
  CHECK(keep_last.dropped() == 3);
  CHECK(keep_last.take().empty());

  LocalInbox keep_all(*loop, 0);
  for (int i = 1; i <= 100; ++i)
    keep_all.push(sample(i));
  CHECK(keep_all.take().size() == 100);
  CHECK(keep_all.dropped() == 0);
}

TEST_CASE("an in-host topic hands one shared sample to each reader and counts its ends",
          "[component]") {
  auto loop = idle_loop();
  auto topic = LocalTopics::instance().join("local_topics_test_a", PortType::Samples);
  REQUIRE(topic.has_value());
  auto first = std::make_shared<LocalInbox>(*loop, 8);
  auto second = std::make_shared<LocalInbox>(*loop, 8);
  (*topic)->add_reader(first);
  (*topic)->add_reader(second);
  (*topic)->add_writer();
  CHECK((*topic)->readers() == 2);
  CHECK((*topic)->writers() == 1);
  const auto s = sample(42);
  CHECK((*topic)->publish(s) == 2);
  auto a = first->take();
  auto b = second->take();
  REQUIRE(a.size() == 1);
  REQUIRE(b.size() == 1);
  CHECK(a[0].get() == s.get()); // the same value, not a copy per reader
  CHECK(b[0].get() == s.get());
  (*topic)->remove_reader(first.get());
  CHECK((*topic)->publish(sample(1)) == 1);
  CHECK(first->take().empty());

  // The same name is the same topic while a connection holds it, and keeps its type.
  auto again = LocalTopics::instance().join("local_topics_test_a", PortType::Samples);
  REQUIRE(again.has_value());
  CHECK(again->get() == topic->get());
  auto other_type = LocalTopics::instance().join("local_topics_test_a", PortType::Command);
  REQUIRE_FALSE(other_type.has_value());
  CHECK(other_type.error() == "local topic \"local_topics_test_a\" carries " +
                                  std::string(port::to_string(PortType::Samples)) + ", not " +
                                  std::string(port::to_string(PortType::Command)));
}
