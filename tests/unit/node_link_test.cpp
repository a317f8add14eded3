// The node link (protocol/node_link.hpp) from the process's side: a NodeLink on one end of a real
// socket pair, this test as the node on the other. Requests come in and are answered, calls go
// out and come back with their errors whole, and the end of the link fails what waits on it.
#include <catch2/catch.hpp>

#include <filesystem>
#include <random>
#include <thread>

#include <time.h>

#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include "control/link_socket.hpp"
#include "control/node_link.hpp"
#include "link_peer.hpp"

using namespace rsca;
namespace link_frames = rsca::protocol::link;

namespace {

struct LinkEnds {
  std::unique_ptr<control::NodeLink> link;
  std::unique_ptr<test::LinkPeer> node;
};

LinkEnds make_link_ends(const std::string &address) {
  auto pair = control::make_link_pair();
  REQUIRE(pair.has_value());
  auto link = control::NodeLink::open(std::move(pair->second), address);
  REQUIRE(link.has_value());
  return {std::move(*link), std::make_unique<test::LinkPeer>(std::move(pair->first))};
}

} // namespace

TEST_CASE("node link: a request from the node is served at its address and answered",
          "[node-link]") {
  auto [link, node] = make_link_ends("d/component/app.1.1/C_1");
  link->on("d/component/app.1.1/C_1", "component.query",
           [](const control::Json &body, const control::RequestContext &context) {
             return control::CallResult<control::Json>(
                 control::Json{{"asked", body.at("ids")}, {"by", context.sender}});
           });
  REQUIRE(
      node->writer->send(link_frames::Request{"7", "d/component/app.1.1/C_1", "component.query",
                                              "d/domain", 1000, control::Json{{"ids", {"x"}}}}));
  auto frame = node->next();
  auto *reply = std::get_if<link_frames::Reply>(&frame);
  REQUIRE(reply != nullptr);
  CHECK(reply->id == "7");
  CHECK(reply->status == 0);
  CHECK(reply->body.at("by") == "d/domain");
  CHECK(reply->body.at("asked") == control::Json{"x"});

  // An operation nobody serves there is a clear bad request, not silence.
  REQUIRE(node->writer->send(link_frames::Request{
      "8", "d/component/app.1.1/C_1", "component.start", "d/domain", 1000, {}}));
  frame = node->next();
  reply = std::get_if<link_frames::Reply>(&frame);
  REQUIRE(reply != nullptr);
  CHECK(reply->status == static_cast<int>(protocol::Status::BadRequest));
  CHECK_THAT(reply->error, Catch::Contains("component.start"));
}

TEST_CASE("node link: a call goes to the node and its error comes back with every detail",
          "[node-link]") {
  auto [link, node] = make_link_ends("d/component/app.1.1/C_1");
  auto result =
      link->call("d/domain", "domain.connection_problem", {{"n", 1}}, std::chrono::seconds(5));
  auto frame = node->next();
  auto *request = std::get_if<link_frames::Request>(&frame);
  REQUIRE(request != nullptr);
  CHECK(request->target == "d/domain");
  CHECK(request->sender == "d/component/app.1.1/C_1");
  CHECK(request->timeout_ms == 5000);
  REQUIRE(node->writer->send(
      link_frames::Reply{request->id, static_cast<int>(protocol::Status::Rejected), "no room",
                         control::Json{{"details", {"first", "second"}}}}));
  const auto answer = result.get();
  REQUIRE_FALSE(answer.has_value());
  CHECK(answer.error().status == protocol::Status::Rejected);
  CHECK(answer.error().message == "no room");
  CHECK(answer.error().details == std::vector<std::string>{"first", "second"});
}

namespace {
// CPU time this process used while it waited `wall` with nothing to do.
std::chrono::nanoseconds cpu_while_idle(std::chrono::milliseconds wall) {
  const auto cpu_now = [] {
    timespec ts{};
    ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return std::chrono::seconds(ts.tv_sec) + std::chrono::nanoseconds(ts.tv_nsec);
  };
  const auto before = cpu_now();
  std::this_thread::sleep_for(wall); // the idle time observed, not a wait for a condition
  return cpu_now() - before;
}
} // namespace

TEST_CASE("node link: a link waiting on a long call is idle, not spinning", "[node-link]") {
  auto [link, node] = make_link_ends("d/component/app.1.1/C_1");
  // Each call wakes the reader to learn its deadline; the wake must not stay pending.
  auto waiting = link->call("d/domain", "x", {}, std::chrono::seconds(60));
  node->next();
  const auto used = cpu_while_idle(std::chrono::milliseconds(300));
  CHECK(used < std::chrono::milliseconds(100)); // a spinning reader takes all 300
}

TEST_CASE("node link: an unanswered call times out, and the link's end fails the rest at once",
          "[node-link]") {
  auto [link, node] = make_link_ends("d/component/app.1.1/C_1");
  auto late = link->call("d/domain", "x", {}, std::chrono::milliseconds(50));
  CHECK(late.get().error().status == protocol::Status::Timeout);

  auto waiting = link->call("d/domain", "x", {}, std::chrono::seconds(60));
  node->next();     // the first request
  node->next();     // the second
  node->fd.reset(); // the node is gone
  REQUIRE(waiting.wait_for(std::chrono::seconds(10)) == std::future_status::ready);
  const auto failed = waiting.get();
  REQUIRE_FALSE(failed.has_value());
  CHECK(failed.error().status == protocol::Status::Unavailable);
}

TEST_CASE("node link: announcements, withdrawals and routes go to the node as frames",
          "[node-link]") {
  auto [link, node] = make_link_ends("d/component/app.1.1/C_1");
  REQUIRE(link->announce("d/component/app.1.1/C_1", "component", {{"pid", 1}}));
  link->route("d/component/app.1.1/C_2", "d/node/n1");
  link->withdraw("d/component/app.1.1/C_1");
  auto a = node->next();
  REQUIRE(std::holds_alternative<link_frames::Announce>(a));
  CHECK(std::get<link_frames::Announce>(a).body.at("pid") == 1);
  auto r = node->next();
  REQUIRE(std::holds_alternative<link_frames::Route>(r));
  CHECK(std::get<link_frames::Route>(r).via == "d/node/n1");
  CHECK(std::holds_alternative<link_frames::Withdraw>(node->next()));
}

TEST_CASE("node link: frames are cut whole from partial reads, an oversized or foreign one ends "
          "the link",
          "[node-link]") {
  auto pair = control::make_link_pair();
  REQUIRE(pair.has_value());
  const int out = pair->first.get();
  const int in = pair->second.get();
  const std::string text = link_frames::encode_frame(link_frames::Withdraw{"a"}).dump();
  const std::string wire = std::string("\0\0\0", 3) + static_cast<char>(text.size()) + text;
  control::FrameReader reader;
  std::vector<link_frames::Frame> frames;
  std::string why;
  // The frame in two pieces: nothing after the first, the whole frame after the second.
  REQUIRE(::send(out, wire.data(), 6, 0) == 6);
  REQUIRE(reader.read_from(in, frames, why));
  CHECK(frames.empty());
  REQUIRE(::send(out, wire.data() + 6, wire.size() - 6, 0) ==
          static_cast<ssize_t>(wire.size() - 6));
  REQUIRE(reader.read_from(in, frames, why));
  REQUIRE(frames.size() == 1);
  CHECK(std::get<link_frames::Withdraw>(frames[0]).address == "a");

  SECTION("over the size limit") {
    const char huge[4] = {0x7f, 0, 0, 0};
    REQUIRE(::send(out, huge, 4, 0) == 4);
    CHECK_FALSE(reader.read_from(in, frames, why));
    CHECK_THAT(why, Catch::Contains("limit"));
  }
  SECTION("a frame of a kind the protocol does not have") {
    const std::string bad = R"({"shutdown":{}})";
    const std::string framed = std::string("\0\0\0", 3) + static_cast<char>(bad.size()) + bad;
    REQUIRE(::send(out, framed.data(), framed.size(), 0) == static_cast<ssize_t>(framed.size()));
    CHECK_FALSE(reader.read_from(in, frames, why));
    CHECK_THAT(why, Catch::Contains("shutdown"));
  }
}

TEST_CASE("node link: the control socket's file is never more open than 0660, whatever the umask",
          "[node-link]") {
  const auto path = std::filesystem::temp_directory_path() /
                    fmt::format("rsca-mode-{}-{}.sock", getpid(), std::random_device{}());
  const mode_t old_umask = ::umask(0);
  auto bound = control::detail::bind_unix_socket(path.string(), 0660);
  ::umask(old_umask);
  REQUIRE(bound.has_value());
  struct stat st {};
  REQUIRE(::stat(path.c_str(), &st) == 0);
  CHECK((st.st_mode & 0777) == 0660); // as bound, before any chmod
  std::filesystem::remove(path);

  ::umask(0077); // takes the group's bits at bind; the listener gives them back
  auto listening = control::listen_for_links(path.string());
  ::umask(old_umask);
  REQUIRE(listening.has_value());
  REQUIRE(::stat(path.c_str(), &st) == 0);
  CHECK((st.st_mode & 0777) == 0660);
  std::filesystem::remove(path);
}
