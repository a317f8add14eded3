// The node's end of the node links (node/process_links.hpp) with real DDS endpoints: a caller
// reaches a process's address through the node, the process's announcements are published for
// it (and only for addresses it was started to serve), and the end of its link fails at once
// what waits on it. The process is this test, on the other end of a real socket pair.
#include <catch2/catch.hpp>

#include <filesystem>
#include <random>
#include <set>
#include <thread>

#include <unistd.h>

#include "control/link_socket.hpp"
#include "link_peer.hpp"
#include "node/host_data.hpp"
#include "node/process_links.hpp"
#include "protocol/component_ops.hpp"
#include "test_domain.hpp"

using namespace rsca;
using namespace std::chrono_literals;
namespace link_msgs = rsca::protocol::link;

namespace {

constexpr const char *kLinkedChild = "t/component/app.1.1/C_1";
constexpr const char *kLinkingNode = "t/node/n1";

// A node endpoint with its links, a process linked to it, and a caller that follows
// announcements (so it learns the way to the process's address, as the domain does).
struct LinksRig {
  std::shared_ptr<dds::Participant> participant = test::participant();
  std::unique_ptr<control::Endpoint> node;
  std::unique_ptr<node::ProcessLinks> links;
  std::unique_ptr<control::Endpoint> caller;
  std::unique_ptr<test::LinkPeer> process;
  std::vector<control::AnnouncementEvent> heard;
  std::mutex heard_mutex;

  explicit LinksRig(node::HostData *host_data = nullptr) {
    auto n = control::Endpoint::open(participant, kLinkingNode);
    REQUIRE(n.has_value());
    node = std::move(*n);
    auto l = node::ProcessLinks::start(*node, host_data);
    REQUIRE(l.has_value());
    links = std::move(*l);
    control::EndpointOptions options;
    options.on_announcement = [this](const control::AnnouncementEvent &e) {
      std::lock_guard lock(heard_mutex);
      heard.push_back(e);
    };
    auto c = control::Endpoint::open(participant, "t/cli/test", options);
    REQUIRE(c.has_value());
    caller = std::move(*c);
    auto pair = control::make_link_pair();
    REQUIRE(pair.has_value());
    links->attach(4242, std::move(pair->first), {kLinkedChild});
    process = std::make_unique<test::LinkPeer>(std::move(pair->second));
  }
  ~LinksRig() {
    links->close();
    caller.reset();
    node.reset();
  }
  bool heard_alive(const std::string &address) {
    std::lock_guard lock(heard_mutex);
    for (const auto &e : heard)
      if (e.address == address && e.kind == control::AnnouncementEvent::Kind::Alive)
        return true;
    return false;
  }
};

template <typename Condition>
bool links_eventually(Condition condition) {
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (std::chrono::steady_clock::now() < deadline) {
    if (condition())
      return true;
    std::this_thread::sleep_for(10ms);
  }
  return false;
}

} // namespace

TEST_CASE("process links: a call to the process's address goes through its node and back",
          "[process-links]") {
  LinksRig rig;
  REQUIRE(
      rig.process->writer->send(link_msgs::Announce{kLinkedChild, "component", {{"pid", 4242}}}));
  REQUIRE(links_eventually([&] { return rig.heard_alive(kLinkedChild); }));
  {
    std::lock_guard lock(rig.heard_mutex);
    for (const auto &e : rig.heard)
      if (e.address == kLinkedChild)
        CHECK(e.body.at(control::kAnnouncedVia) == kLinkingNode); // the node says it serves it
  }
  // The caller routes through the node from the announcement alone.
  auto reply = rig.caller->call(kLinkedChild, "component.status", {{"x", 1}}, 10s);
  auto frame = rig.process->next();
  auto *request = std::get_if<link_msgs::Request>(&frame);
  REQUIRE(request != nullptr);
  CHECK(request->target == kLinkedChild);
  CHECK(request->operation == "component.status");
  CHECK(request->sender == "t/cli/test");
  CHECK(request->body.at("x") == 1);
  REQUIRE(rig.process->writer->send(link_msgs::Reply{request->id, 0, "", {{"state", "started"}}}));
  const auto answer = reply.get();
  REQUIRE(answer.has_value());
  CHECK(answer->at("state") == "started");
}

TEST_CASE("process links: a process announces only what it was started to serve",
          "[process-links]") {
  LinksRig rig;
  REQUIRE(rig.process->writer->send(
      link_msgs::Announce{"t/component/app.1.1/SOMEONE_ELSE", "component", {{"pid", 1}}}));
  REQUIRE(
      rig.process->writer->send(link_msgs::Announce{kLinkedChild, "component", {{"pid", 4242}}}));
  REQUIRE(links_eventually([&] { return rig.heard_alive(kLinkedChild); }));
  // Frames are taken in order: the foreign one came first and was not published.
  CHECK_FALSE(rig.heard_alive("t/component/app.1.1/SOMEONE_ELSE"));
}

TEST_CASE("process links: the end of a process's link fails its calls at once and withdraws it",
          "[process-links]") {
  LinksRig rig;
  REQUIRE(
      rig.process->writer->send(link_msgs::Announce{kLinkedChild, "component", {{"pid", 4242}}}));
  REQUIRE(links_eventually([&] { return rig.heard_alive(kLinkedChild); }));
  auto reply = rig.caller->call(kLinkedChild, "component.release", {}, 30s);
  REQUIRE(std::holds_alternative<link_msgs::Request>(rig.process->next()));
  const auto ended = std::chrono::steady_clock::now();
  rig.process->fd.reset(); // the process dies without answering
  REQUIRE(reply.wait_for(10s) == std::future_status::ready);
  const auto answer = reply.get();
  REQUIRE_FALSE(answer.has_value());
  CHECK(answer.error().status == protocol::Status::Unavailable);
  CHECK_THAT(answer.error().message, Catch::Contains("4242"));
  // Well before the call's own 30 s: the node saw the link end.
  CHECK(std::chrono::steady_clock::now() - ended < 10s);
  REQUIRE(links_eventually([&] {
    std::lock_guard lock(rig.heard_mutex);
    return !rig.heard.empty() && rig.heard.back().address == kLinkedChild &&
           rig.heard.back().kind == control::AnnouncementEvent::Kind::Gone;
  }));
  // Once reaped, the address is served no longer: a call fails, it does not hang.
  rig.links->detach(4242);
  auto after = rig.caller->call_sync(kLinkedChild, "component.status", {}, 2s);
  REQUIRE_FALSE(after.has_value());
}

TEST_CASE("process links: a process's own call is made on DDS by its node", "[process-links]") {
  LinksRig rig;
  rig.caller->on("test.echo", [](const control::Json &body, const control::RequestContext &c) {
    return control::CallResult<control::Json>(control::Json{{"echo", body}, {"from", c.sender}});
  });
  REQUIRE(rig.process->writer->send(
      link_msgs::Request{"1", "t/cli/test", "test.echo", kLinkedChild, 5000, {{"n", 7}}}));
  auto frame = rig.process->next();
  auto *reply = std::get_if<link_msgs::Reply>(&frame);
  REQUIRE(reply != nullptr);
  CHECK(reply->id == "1");
  REQUIRE(reply->status == 0);
  CHECK(reply->body.at("echo").at("n") == 7);
  CHECK(reply->body.at("from") == kLinkingNode); // the node made it
}

TEST_CASE("process links: a relayed connect that asks for shared memory gets its ring from the "
          "host's data, which lets the end go with the process",
          "[process-links]") {
  auto data = node::HostData::create({}, 64 << 20).value();
  LinksRig rig(data.get());
  rig.caller->route(kLinkedChild, kLinkingNode);
  protocol::component::ConnectRequest connect;
  connect.connection = "c1";
  connect.port = "in";
  connect.direction = "provides";
  connect.repid = "IDL:rsca/SampleSeq:1.0";
  connect.topic = "t_topic_c1";
  connect.shared_memory = true;
  auto answer = [&](int status) {
    auto frame = rig.process->next();
    auto *request = std::get_if<link_msgs::Request>(&frame);
    REQUIRE(request != nullptr);
    auto relayed = protocol::decode<protocol::component::ConnectRequest>(request->body);
    REQUIRE(relayed.has_value());
    REQUIRE(relayed->ring.has_value()); // the node added the ring it made
    CHECK(relayed->ring->offset != 0);
    REQUIRE(rig.process->writer->send(
        link_msgs::Reply{request->id, status, status == 0 ? "" : "refused", {}}));
  };
  // Made: the end is counted once the process said so.
  auto made = rig.caller->call(kLinkedChild, "component.connect", protocol::encode(connect), 10s);
  answer(0);
  REQUIRE(made.get().has_value());
  CHECK(data->counts().rings == 1);
  CHECK(data->counts().ends == 1);
  // Refused by the process: its new end goes, the one it had stays. (The node lets it go just
  // after it relayed the reply: the caller may have the reply first.)
  auto refused =
      rig.caller->call(kLinkedChild, "component.connect", protocol::encode(connect), 10s);
  answer(static_cast<int>(protocol::Status::Failed));
  CHECK_FALSE(refused.get().has_value());
  CHECK(links_eventually([&] { return data->counts().ends == 1; }));
  CHECK(data->counts().rings == 1);
  // The process ends: its end and the ring go.
  rig.links->detach(4242);
  CHECK(data->counts().ends == 0);
  CHECK(data->counts().rings == 0);
}

TEST_CASE("process links: a client of the control socket may call, not announce",
          "[process-links]") {
  LinksRig rig;
  rig.caller->on("test.echo", [](const control::Json &body, const control::RequestContext &c) {
    return control::CallResult<control::Json>(control::Json{{"echo", body}, {"from", c.sender}});
  });
  const auto path = std::filesystem::temp_directory_path() /
                    fmt::format("rsca-links-{}-{}.sock", getpid(), std::random_device{}());
  REQUIRE(rig.links->listen(path.string()).has_value());
  CHECK_FALSE(rig.links->listen(path.string()).has_value()); // one socket per node
  auto fd = control::connect_link(path.string());
  REQUIRE(fd.has_value());
  test::LinkPeer client(std::move(*fd));
  // The link's hello is answered by the node itself.
  REQUIRE(client.writer->send(link_msgs::Request{"1", link_msgs::kHelloTarget,
                                                 link_msgs::kHelloOperation, "t/cli/me", 1000,
                                                 control::Json::object()}));
  auto hello = client.next();
  auto *hello_reply = std::get_if<link_msgs::Reply>(&hello);
  REQUIRE(hello_reply != nullptr);
  REQUIRE(hello_reply->status == 0);
  CHECK(hello_reply->body.at("node") == kLinkingNode);
  // Frames are taken in order: the announcement is refused before the call is made.
  REQUIRE(client.writer->send(link_msgs::Announce{kLinkedChild, "component", {{"pid", 1}}}));
  REQUIRE(client.writer->send(
      link_msgs::Request{"9", "t/cli/test", "test.echo", "t/cli/me", 5000, {{"n", 3}}}));
  auto frame = client.next();
  auto *reply = std::get_if<link_msgs::Reply>(&frame);
  REQUIRE(reply != nullptr);
  CHECK(reply->id == "9");
  REQUIRE(reply->status == 0);
  CHECK(reply->body.at("echo").at("n") == 3);
  CHECK(reply->body.at("from") == kLinkingNode);
  CHECK_FALSE(rig.heard_alive(kLinkedChild));
  rig.links->close();
  CHECK_FALSE(std::filesystem::exists(path)); // the socket file goes with the links
}

TEST_CASE("process links: a control socket path too long or in no folder is refused",
          "[process-links]") {
  LinksRig rig;
  auto too_long = rig.links->listen("/tmp/" + std::string(200, 'x') + ".sock");
  REQUIRE_FALSE(too_long.has_value());
  CHECK_THAT(too_long.error().to_string(), Catch::Contains("Unix socket"));
  CHECK_FALSE(rig.links->listen("/nonexistent-folder/node.sock").has_value());
}

TEST_CASE("process links: a control socket another node listens on is not taken over",
          "[process-links]") {
  LinksRig first, second;
  const auto path = std::filesystem::temp_directory_path() /
                    fmt::format("rsca-links-{}-{}.sock", getpid(), std::random_device{}());
  REQUIRE(first.links->listen(path.string()).has_value());
  auto taken = second.links->listen(path.string());
  REQUIRE_FALSE(taken.has_value());
  CHECK_THAT(taken.error().to_string(), Catch::Contains("another process listens there"));
  CHECK(control::connect_link(path.string()).has_value()); // still the first's
  first.links->close();
  // Now a stale file nobody accepts on: replaced.
  std::filesystem::path stale = path;
  stale += ".stale";
  {
    auto fd = control::listen_for_links(stale.string());
    REQUIRE(fd.has_value());
  } // closed: the file stays
  REQUIRE(std::filesystem::exists(stale));
  CHECK(second.links->listen(stale.string()).has_value());
  CHECK(control::connect_link(stale.string()).has_value());
}

TEST_CASE("process links: a client has at most 8 calls under way, one more is refused at once",
          "[process-links]") {
  LinksRig rig;
  std::promise<void> gate;
  std::shared_future<void> opened = gate.get_future().share();
  rig.caller->on("test.wait", [opened](const control::Json &, const control::RequestContext &) {
    opened.wait();
    return control::CallResult<control::Json>(control::Json::object());
  });
  const auto path = std::filesystem::temp_directory_path() /
                    fmt::format("rsca-links-{}-{}.sock", getpid(), std::random_device{}());
  REQUIRE(rig.links->listen(path.string()).has_value());
  auto fd = control::connect_link(path.string());
  REQUIRE(fd.has_value());
  test::LinkPeer client(std::move(*fd));
  for (int i = 1; i <= 9; ++i)
    REQUIRE(client.writer->send(link_msgs::Request{std::to_string(i), "t/cli/test", "test.wait",
                                                   "t/cli/me", 5000, control::Json::object()}));
  // The ninth is answered first, refused; the eight others once the handler lets them go.
  auto frame = client.next();
  auto *refused = std::get_if<link_msgs::Reply>(&frame);
  REQUIRE(refused != nullptr);
  CHECK(refused->id == "9");
  CHECK(refused->status == static_cast<std::int32_t>(protocol::Status::Rejected));
  gate.set_value();
  std::set<std::string> answered;
  for (int i = 0; i < 8; ++i) {
    auto next = client.next();
    auto *reply = std::get_if<link_msgs::Reply>(&next);
    REQUIRE(reply != nullptr);
    CHECK(reply->status == 0);
    answered.insert(reply->id);
  }
  CHECK(answered.size() == 8);
  CHECK_FALSE(answered.contains("9"));
}
