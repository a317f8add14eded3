// An endpoint's replies on their way (control/reply_ways.hpp): held for a caller whose reader has
// not come, never on a thread; sent when it comes; dropped with their way at their time; the ways
// bounded (issue 37, defect 4).
#include <catch2/catch.hpp>

#include "control.h" // generated from dds/control.idl
#include "control/reply_ways.hpp"
#include "eventually.hpp"
#include "test_domain.hpp"
#include "writers_into.hpp"

using namespace rsca;
using control::ReplyWays;
using rsca::test::eventually;
using rsca::test::writers_into;

namespace {

struct Ways {
  std::shared_ptr<dds::Participant> pp = test::participant();
  dds::Qos qos = [] {
    auto q = dds::make_qos();
    dds_qset_reliability(q.get(), DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_history(q.get(), DDS_HISTORY_KEEP_ALL, 0);
    return q;
  }();
  dds::Entity topic{
      dds_create_topic(pp->get(), &rsca_ctl_Reply_desc, "rsca_ctl_Reply", qos.get(), nullptr)};
  dds::Entity waitset{dds_create_waitset(pp->get())};
  ReplyWays ways{pp->get(), topic.get(), qos.get(), waitset.get()};

  // A reader of the replies into `partition`.
  dds::Entity reader(const std::string &partition) {
    auto pqos = dds::make_qos();
    const char *names[] = {partition.c_str()};
    dds_qset_partition(pqos.get(), 1, names);
    const dds_entity_t subscriber = dds_create_subscriber(pp->get(), pqos.get(), nullptr);
    return dds::Entity(dds_create_reader(subscriber, topic.get(), qos.get(), nullptr));
  }
};

ReplyWays::Reply reply(const std::string &id) {
  return {id, 0, "", "{}", {}};
}

} // namespace

TEST_CASE("reply ways: a reply whose caller's reader has not come is held, and sent when it comes",
          "[control][reply-ways]") {
  Ways w;
  REQUIRE(w.ways.post("test/late", reply("late#1")).has_value()); // returns at once
  CHECK(w.ways.held() == 1);
  auto reader = w.reader("test/late");
  REQUIRE(reader.get() > 0);
  REQUIRE(eventually([&] {
    w.ways.flush();
    return w.ways.held() == 0;
  }));
  std::string got;
  REQUIRE(eventually([&] {
    void *samples[1] = {nullptr};
    dds_sample_info_t info;
    if (dds_take(reader.get(), samples, &info, 1, 1) == 1) {
      if (info.valid_data)
        got = static_cast<const rsca_ctl_Reply *>(samples[0])->id;
      dds_return_loan(reader.get(), samples, 1);
    }
    return !got.empty();
  }));
  CHECK(got == "late#1");
  // Its reader came: the way stays past the reply's time.
  w.ways.flush(ReplyWays::Clock::now() + ReplyWays::kWait + std::chrono::seconds(1));
  CHECK(writers_into(w.pp, "rsca_ctl_Reply", "test/late") == 1);
}

TEST_CASE("reply ways: a reply nobody reads is dropped at its time, and its way with it",
          "[control][reply-ways]") {
  Ways w;
  REQUIRE(w.ways.post("test/void", reply("void#1")).has_value());
  CHECK(w.ways.held() == 1);
  CHECK(writers_into(w.pp, "rsca_ctl_Reply", "test/void") == 1);
  w.ways.flush(); // not yet its time
  CHECK(w.ways.held() == 1);
  w.ways.flush(ReplyWays::Clock::now() + ReplyWays::kWait + std::chrono::seconds(1));
  CHECK(w.ways.held() == 0);
  CHECK(w.ways.ways() == 0); // its writer deleted
}

TEST_CASE("reply ways: at most kMaxWays ways and kMaxHeld replies, the oldest making room",
          "[control][reply-ways]") {
  Ways w;
  for (std::size_t i = 0; i < ReplyWays::kMaxWays + 40; ++i)
    REQUIRE(w.ways.post(fmt::format("test/many/{}", i), reply(fmt::format("m#{}", i))).has_value());
  CHECK(w.ways.ways() == ReplyWays::kMaxWays);
  for (std::size_t i = 0; i < ReplyWays::kMaxHeld; ++i)
    REQUIRE(w.ways.post("test/one", reply(fmt::format("o#{}", i))).has_value());
  CHECK(w.ways.held() == ReplyWays::kMaxHeld);
  auto refused = w.ways.post("test/*", reply("p#1"));
  REQUIRE_FALSE(refused.has_value());
  CHECK(refused.error().status == control::Status::BadRequest);
}
