// The control plane between real DDS participants in one process, on a DDS domain of its own.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <future>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <unistd.h>
#include <vector>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "control/endpoint.hpp"
#include "eventually.hpp"
#include "protocol/codec.hpp"
#include "test_domain.hpp"
#include "writers_into.hpp"

using namespace rsca;
using namespace std::chrono_literals;
using control::Endpoint;
using control::Json;
using control::Status;
using rsca::test::writers_into;

using rsca::test::eventually;

namespace {

std::unique_ptr<Endpoint> open(const std::shared_ptr<dds::Participant> &pp,
                               const std::string &address, control::EndpointOptions options = {}) {
  auto endpoint = Endpoint::open(pp, address, options);
  REQUIRE(endpoint.has_value());
  return std::move(*endpoint);
}

// Holds handlers until opened, so that a test controls when a call is answered.
class Gate {
public:
  control::CallResult<Json> wait() {
    std::unique_lock lock(m_);
    cv_.wait(lock, [&] { return open_; });
    return Json{};
  }
  void open() {
    {
      std::lock_guard lock(m_);
      open_ = true;
    }
    cv_.notify_all();
  }

private:
  std::mutex m_;
  std::condition_variable cv_;
  bool open_ = false;
};

// Polls `done` until it holds or 5 s have passed.
control::CallResult<Json> fast(const Json &, const control::RequestContext &) {
  return Json{{"ok", true}};
}

} // namespace

TEST_CASE("a call reaches the addressed endpoint and its reply comes back", "[control]") {
  auto pp = test::participant();
  auto server = open(pp, "test/server");
  auto other = open(pp, "test/other");
  std::atomic<int> other_calls{0};
  server->on("add",
             [](const Json &body, const control::RequestContext &ctx) -> control::CallResult<Json> {
               return Json{{"sum", body.at("a").get<int>() + body.at("b").get<int>()},
                           {"from", ctx.sender}};
             });
  other->on("add", [&](const Json &, const control::RequestContext &) -> control::CallResult<Json> {
    ++other_calls;
    return Json{};
  });
  auto client = open(pp, "test/client");
  auto reply = client->call_sync("test/server", "add", Json{{"a", 2}, {"b", 40}}, 5s);
  REQUIRE(reply.has_value());
  CHECK(reply->at("sum") == 42);
  CHECK(reply->at("from") == "test/client");
  CHECK(other_calls == 0); // partitions keep requests to their addressee
}

TEST_CASE(
    "a reply's bytes travel beside its JSON, whole, and a reply that cannot be text fails the "
    "call, not the endpoint",
    "[control]") {
  auto pp = test::participant();
  auto server = open(pp, "test/server");
  protocol::Bytes::container_type bytes(3 * 1024 * 1024 + 7);
  for (std::size_t i = 0; i < bytes.size(); ++i)
    bytes[i] = static_cast<std::uint8_t>(i * 131 + (i >> 9));
  server->on("read",
             [&](const Json &, const control::RequestContext &) -> control::CallResult<Json> {
               return Json{{"size", bytes.size()}, {protocol::kPayloadField, Json::binary(bytes)}};
             });
  server->on("nested",
             [&](const Json &, const control::RequestContext &) -> control::CallResult<Json> {
               return Json{{"name", std::string("\xff\xfe not UTF-8")}};
             });
  auto client = open(pp, "test/client");
  auto reply = client->call_sync("test/server", "read", Json::object(), 10s);
  REQUIRE(reply.has_value());
  CHECK(reply->at("size") == bytes.size());
  REQUIRE(reply->at(protocol::kPayloadField).is_binary());
  const protocol::Bytes::container_type &got = reply->at(protocol::kPayloadField).get_binary();
  CHECK(got == bytes);
  auto nested = client->call_sync("test/server", "nested", Json::object(), 5s);
  REQUIRE_FALSE(nested.has_value());
  CHECK(nested.error().status == Status::Failed);
  CHECK(client->call_sync("test/server", "read", Json::object(), 10s).has_value());
}

TEST_CASE("errors travel back with their status", "[control]") {
  auto pp = test::participant();
  auto server = open(pp, "test/server");
  server->on("fail",
             [](const Json &, const control::RequestContext &) -> control::CallResult<Json> {
               return control::call_error(Status::Rejected, "not enough memory on gpp@node2");
             });
  auto client = open(pp, "test/client");
  auto reply = client->call_sync("test/server", "fail", Json::object(), 5s);
  REQUIRE_FALSE(reply.has_value());
  CHECK(reply.error().status == Status::Rejected);
  CHECK(reply.error().message == "not enough memory on gpp@node2");

  CHECK(reply.error().details.empty());

  // Findings travel whole: the first says what failed, every one is in the details, also
  // through a batch (call_all to an alias of the server).
  Error findings(Diagnostic{{"a.prf.xml", 3, 7}, "range", "rate_hz is -1, below 0"});
  findings.add(Diagnostic{{}, "name", "the port \"a/b\" is not a name"});
  server->on("findings",
             [&](const Json &, const control::RequestContext &) -> control::CallResult<Json> {
               return control::call_error(Status::BadRequest, findings);
             });
  const std::vector<std::string> details{"a.prf.xml:3:7: range: rate_hz is -1, below 0",
                                         "name: the port \"a/b\" is not a name"};
  auto found = client->call_sync("test/server", "findings", Json::object(), 5s);
  REQUIRE_FALSE(found.has_value());
  CHECK(found.error().message == "rate_hz is -1, below 0 (and 1 more)");
  CHECK(found.error().details == details);
  control::EndpointOptions options;
  options.aliases = {"test/host/a", "test/host/b"};
  auto host = open(pp, "test/host", options);
  for (const std::string alias : {"test/host/a", "test/host/b"})
    host->on(alias, "findings",
             [&](const Json &, const control::RequestContext &) -> control::CallResult<Json> {
               return control::call_error(Status::BadRequest, findings);
             });
  client->route("test/host/a", "test/host");
  client->route("test/host/b", "test/host");
  auto batch = client->call_all(
      {{"test/host/a", "findings", Json::object()}, {"test/host/b", "findings", Json::object()}},
      5s);
  REQUIRE(batch.size() == 2);
  for (const auto &r : batch) {
    REQUIRE_FALSE(r.has_value());
    CHECK(r.error().details == details);
  }

  auto unknown = client->call_sync("test/server", "nope", Json::object(), 5s);
  REQUIRE_FALSE(unknown.has_value());
  CHECK(unknown.error().status == Status::BadRequest);
  CHECK_THAT(unknown.error().message, Catch::Contains("does not serve operation \"nope\""));
}

TEST_CASE("a call to nobody fails when its deadline passes", "[control]") {
  auto pp = test::participant();
  auto client = open(pp, "test/client");
  const auto start = std::chrono::steady_clock::now();
  auto reply = client->call_sync("test/nobody", "x", Json::object(), 300ms);
  REQUIRE_FALSE(reply.has_value());
  CHECK((reply.error().status == Status::Unavailable || reply.error().status == Status::Timeout));
  CHECK(std::chrono::steady_clock::now() - start < 5s);
}

TEST_CASE("a slow handler times out the caller but does not block other calls", "[control]") {
  auto pp = test::participant();
  auto server = open(pp, "test/server");
  Gate gate;
  server->on("slow", [&](const Json &, const control::RequestContext &) { return gate.wait(); });
  server->on("fast", fast);
  auto client = open(pp, "test/client");
  // The server found first, so that the slow call's deadline can only pass after it was sent.
  REQUIRE(client->call_sync("test/server", "fast", Json::object(), 5s).has_value());
  auto slow = client->call("test/server", "slow", Json::object(), 1s);
  auto fast_reply = client->call_sync("test/server", "fast", Json::object(), 5s);
  CHECK(fast_reply.has_value());
  auto slow_result = slow.get();
  REQUIRE_FALSE(slow_result.has_value());
  CHECK(slow_result.error().status == Status::Timeout);
  gate.open();
}

TEST_CASE("calls to an endpoint known to be dead are abandoned at once, with the reason",
          "[control]") {
  auto pp = test::participant();
  auto server = open(pp, "test/server");
  Gate gate;
  server->on("hang", [&](const Json &, const control::RequestContext &) { return gate.wait(); });
  server->on("fast", fast);
  auto other = open(pp, "test/other");
  other->on("fast", fast);
  auto client = open(pp, "test/client");
  REQUIRE(client->call_sync("test/server", "fast", Json::object(), 5s).has_value());
  // The deadline is far: only abandon can end this call before the test's end.
  auto hanging = client->call("test/server", "hang", Json::object(), 1h);
  client->abandon("test/server", "its node is gone");
  REQUIRE(hanging.wait_for(10s) == std::future_status::ready);
  auto result = hanging.get();
  REQUIRE_FALSE(result.has_value());
  CHECK(result.error().status == Status::Unavailable);
  CHECK(result.error().message == "test/server to \"hang\": its node is gone");
  // Calls to other addresses are untouched.
  CHECK(client->call_sync("test/other", "fast", Json::object(), 5s).has_value());
  gate.open();
}

TEST_CASE("announcements are seen, updated and withdrawn", "[control]") {
  auto pp = test::participant();
  std::mutex m;
  std::condition_variable cv;
  std::vector<control::AnnouncementEvent> events;
  auto watcher = open(pp, "test/watcher",
                      {.workers = 1,
                       .senders = 4,
                       .on_announcement =
                           [&](const control::AnnouncementEvent &e) {
                             std::lock_guard lock(m);
                             events.push_back(e);
                             cv.notify_all();
                           },
                       .aliases = {},
                       .prepare_kinds = {}});
  auto wait_for = [&](auto predicate) {
    std::unique_lock lock(m);
    return cv.wait_for(lock, 5s, [&] { return predicate(events); });
  };
  {
    auto node = open(pp, "test/node1");
    REQUIRE(node->announce("node", Json{{"devices", 1}}).has_value());
    CHECK(wait_for([](const auto &ev) {
      return !ev.empty() && ev.back().address == "test/node1" &&
             ev.back().kind == control::AnnouncementEvent::Kind::Alive &&
             ev.back().body.at("devices") == 1;
    }));
    REQUIRE(node->announce("node", Json{{"devices", 2}}).has_value());
    CHECK(wait_for([](const auto &ev) { return ev.back().body.value("devices", 0) == 2; }));
  } // the endpoint goes without withdrawing: DDS disposes its announcement, with no data
  CHECK(wait_for([](const auto &ev) {
    return ev.back().address == "test/node1" &&
           ev.back().kind == control::AnnouncementEvent::Kind::Gone && !ev.back().withdrawn;
  }));
  auto node2 = open(pp, "test/node2");
  REQUIRE(node2->announce("node", Json::object()).has_value());
  CHECK(wait_for([](const auto &ev) { return ev.back().address == "test/node2"; }));
  node2->withdraw(); // said, not lost
  CHECK(wait_for([](const auto &ev) {
    return ev.back().address == "test/node2" &&
           ev.back().kind == control::AnnouncementEvent::Kind::Gone && ev.back().withdrawn;
  }));
}

TEST_CASE("the way to an endpoint can be prepared before it exists and forgotten after",
          "[control]") {
  auto pp = test::participant();
  auto client = open(pp, "test/client");
  client->prepare("test/later"); // nobody there yet: no error, no wait
  auto server = open(pp, "test/later");
  server->on("ping",
             [](const Json &, const control::RequestContext &) -> control::CallResult<Json> {
               return Json{{"pong", true}};
             });
  auto reply = client->call_sync("test/later", "ping", Json::object(), 5s);
  REQUIRE(reply.has_value());
  CHECK(reply->at("pong") == true);
  // Forgetting drops the writer; a later call makes a new one and still arrives.
  client->forget("test/later");
  reply = client->call_sync("test/later", "ping", Json::object(), 5s);
  REQUIRE(reply.has_value());
  CHECK(reply->at("pong") == true);
}

TEST_CASE("preparing makes the request or reply writer before the first call", "[control]") {
  auto pp = test::participant();
  auto client = open(pp, "test/client");
  CHECK(writers_into(pp, "rsca_ctl_Request", "test/ahead") == 0);
  client->prepare("test/ahead");
  CHECK(writers_into(pp, "rsca_ctl_Request", "test/ahead") == 1);
  client->prepare("test/ahead"); // made once
  CHECK(writers_into(pp, "rsca_ctl_Request", "test/ahead") == 1);
  CHECK(writers_into(pp, "rsca_ctl_Reply", "test/caller") == 0);
  client->prepare_replies("test/caller");
  CHECK(writers_into(pp, "rsca_ctl_Reply", "test/caller") == 1);
}

TEST_CASE("endpoints of a prepared kind get their way made when they announce themselves",
          "[control]") {
  auto pp = test::participant();
  std::atomic<bool> saw_node{false}, saw_monitor{false};
  control::EndpointOptions options;
  options.prepare_kinds = {"node"};
  options.on_announcement = [&](const control::AnnouncementEvent &event) {
    if (event.address == "test/node1")
      saw_node = true;
    if (event.address == "test/monitor")
      saw_monitor = true;
  };
  auto domain = open(pp, "test/domain", options);
  auto node = open(pp, "test/node1");
  auto monitor = open(pp, "test/monitor");
  REQUIRE(node->announce("node", Json::object()).has_value());
  REQUIRE(monitor->announce("monitor", Json::object()).has_value());
  // The way is made before the announcement is handed on, so once both have been seen:
  REQUIRE(eventually([&] { return saw_node && saw_monitor; }));
  CHECK(writers_into(pp, "rsca_ctl_Request", "test/node1") == 1);
  CHECK(writers_into(pp, "rsca_ctl_Request", "test/monitor") == 0);
}

TEST_CASE(
    "an endpoint serves its aliases, and call_all sends the calls routed to it as one request",
    "[control]") {
  auto pp = test::participant();
  control::EndpointOptions options;
  options.aliases = {"test/host/a", "test/host/b"};
  auto host = open(pp, "test/host", options);
  std::mutex m;
  std::vector<std::string> request_ids;
  std::vector<std::chrono::steady_clock::time_point> received;
  for (const std::string name : {"a", "b"})
    host->on("test/host/" + name, "who",
             [&, name](const Json &, const control::RequestContext &ctx) {
               std::lock_guard lock(m);
               request_ids.push_back(ctx.id);
               received.push_back(ctx.received);
               return control::CallResult<Json>(Json{{"me", name}, {"target", ctx.target}});
             });
  auto client = open(pp, "test/client");

  // Straight to an alias's partition, with no route known.
  auto direct = client->call_sync("test/host/b", "who", Json::object(), 5s);
  REQUIRE(direct.has_value());
  CHECK(direct->at("me") == "b");
  CHECK(direct->at("target") == "test/host/b");

  // Routed: three calls to one host travel as one request; each gets its own result.
  client->route("test/host/a", "test/host");
  client->route("test/host/b", "test/host");
  client->route("test/host/c", "test/host");
  request_ids.clear();
  received.clear();
  auto results = client->call_all({{"test/host/a", "who", Json::object()},
                                   {"test/host/b", "who", Json::object()},
                                   {"test/host/a", "nope", Json::object()},
                                   {"test/host/c", "who", Json::object()}},
                                  5s);
  REQUIRE(results.size() == 4);
  REQUIRE(results[0].has_value());
  CHECK(results[0]->at("me") == "a");
  REQUIRE(results[1].has_value());
  CHECK(results[1]->at("me") == "b");
  REQUIRE_FALSE(results[2].has_value());
  CHECK(results[2].error().status == Status::BadRequest);
  CHECK_THAT(results[2].error().message, Catch::Contains("does not serve operation \"nope\""));
  REQUIRE_FALSE(results[3].has_value()); // routed to a host that does not serve it
  CHECK_THAT(results[3].error().message, Catch::Contains("test/host/c does not serve"));
  REQUIRE(request_ids.size() == 2);
  CHECK(request_ids[0] == request_ids[1]);
  // Both count their time from the batch's arrival, although the second ran after the first.
  REQUIRE(received.size() == 2);
  CHECK(received[0] == received[1]);

  // Bad input: a batch without calls, a batch inside a batch.
  auto malformed = client->call_sync("test/host", "endpoint.batch", Json::object(), 5s);
  REQUIRE_FALSE(malformed.has_value());
  CHECK(malformed.error().status == Status::BadRequest);
  CHECK(malformed.error().message == "a batch needs \"calls\", an array");
  auto nested = client->call_sync(
      "test/host", "endpoint.batch",
      Json{{"calls", {{{"target", "test/host/a"}, {"operation", "endpoint.batch"}}}}}, 5s);
  REQUIRE(nested.has_value());
  CHECK(nested->at("results")[0].at("error") == "batches do not nest");

  // A single routed call goes on its own, through the host's partition.
  auto single = client->call_all({{"test/host/a", "who", Json::object()}}, 5s);
  REQUIRE(single.size() == 1);
  REQUIRE(single[0].has_value());
  CHECK(single[0]->at("target") == "test/host/a");
}

TEST_CASE("an alias that is not a valid address is refused at open", "[control]") {
  auto pp = test::participant();
  control::EndpointOptions options;
  options.aliases = {"test/host/a", "test/host/*"};
  auto endpoint = Endpoint::open(pp, "test/host", options);
  REQUIRE_FALSE(endpoint.has_value());
  CHECK_THAT(endpoint.error().to_string(),
             Catch::Contains("\"test/host/*\" is not a valid endpoint address"));
}

TEST_CASE("stop_serving waits for the address's running handler, then the address is not served",
          "[control]") {
  auto pp = test::participant();
  control::EndpointOptions options;
  options.aliases = {"test/host/a"};
  auto host = open(pp, "test/host", options);
  Gate gate;
  std::promise<void> entered;
  host->on("test/host/a", "hold", [&](const Json &, const control::RequestContext &) {
    entered.set_value();
    return gate.wait();
  });
  host->on("test/host/a", "who", fast);
  auto client = open(pp, "test/client");
  auto held = client->call("test/host/a", "hold", Json::object(), 10s);
  entered.get_future().wait();
  auto stopped = std::async(std::launch::async, [&] { host->stop_serving("test/host/a"); });
  CHECK(stopped.wait_for(100ms) == std::future_status::timeout); // the handler still runs
  gate.open();
  stopped.get();
  CHECK(held.get().has_value());
  auto after = client->call_sync("test/host/a", "who", Json::object(), 5s);
  REQUIRE_FALSE(after.has_value());
  CHECK(after.error().status == Status::BadRequest);
}

TEST_CASE("an endpoint keeps reply writers for the callers alive, not one for every caller it had",
          "[control]") {
  // A daemon answering CLI commands: each caller a participant (a process) of its own, gone after
  // its call (issue 18, defect 5: the domain kept a reply writer for every CLI it ever answered).
  auto pp = test::participant();
  auto server = open(pp, "test/server");
  server->on("fast", fast);
  auto call_and_leave = [&](const std::string &address) {
    auto client = open(test::participant(), address);
    REQUIRE(client->call_sync("test/server", "fast", Json::object(), 5s).has_value());
  };
  const int callers = 8;
  for (int i = 0; i < callers; ++i)
    call_and_leave("test/cli-" + std::to_string(i));
  auto replies_to_departed = [&] {
    int n = 0;
    for (int i = 0; i < callers; ++i)
      n += writers_into(pp, "rsca_ctl_Reply", "test/cli-" + std::to_string(i));
    return n;
  };
  CHECK(replies_to_departed() > 0); // dropped when the next way is made, not before
  // The next caller's way is made once the others are known to be gone.
  REQUIRE(eventually([&] {
    call_and_leave("test/cli-next");
    return replies_to_departed() == 0;
  }));
  // A caller that is alive keeps its writer, and is answered again.
  auto alive = open(test::participant(), "test/cli-alive");
  REQUIRE(alive->call_sync("test/server", "fast", Json::object(), 5s).has_value());
  call_and_leave("test/cli-after");
  CHECK(writers_into(pp, "rsca_ctl_Reply", "test/cli-alive") == 1);
  CHECK(alive->call_sync("test/server", "fast", Json::object(), 5s).has_value());
}

TEST_CASE("a call whose addressee leaves DDS before it replies fails then, not at its deadline",
          "[control]") {
  // What a CLI sees when the domain daemon dies during a launch (issue 18, defect 10).
  Gate gate; // outlives the server, whose handler waits on it
  std::atomic<bool> entered{false};
  auto server_pp = test::participant();
  auto server = open(server_pp, "test/server");
  server->on("hang", [&](const Json &, const control::RequestContext &) {
    entered = true;
    return gate.wait();
  });
  server->on("fast", fast);
  auto client = open(test::participant(), "test/client");
  REQUIRE(client->call_sync("test/server", "fast", Json::object(), 5s).has_value());
  auto hanging = client->call("test/server", "hang", Json::object(), 1h);
  REQUIRE(eventually([&] { return entered.load(); }));
  // The server's process vanishes from DDS with the handler still running: its participant and
  // every entity of it are deleted under it.
  dds_delete(server_pp->get());
  REQUIRE(hanging.wait_for(30s) == std::future_status::ready);
  auto result = hanging.get();
  REQUIRE_FALSE(result.has_value());
  CHECK(result.error().status == Status::Unavailable);
  CHECK_THAT(result.error().message, Catch::Contains("test/server left before it replied"));
  gate.open();
}

TEST_CASE("an endpoint that holds requests answers none before it starts serving, then all",
          "[control]") {
  // A daemon registers its handlers after open: a request that came in between must wait for
  // them, not be told the operation is not served (a CLI calling a restarting domain daemon).
  auto pp = test::participant();
  control::EndpointOptions options;
  options.hold_requests = true;
  auto server = open(pp, "test/server", options);
  auto client = open(pp, "test/client");
  auto early = client->call("test/server", "fast", Json::object(), 10s);
  // Received and held: the way is matched, yet no answer comes while nothing serves.
  REQUIRE(eventually([&] { return writers_into(pp, "rsca_ctl_Request", "test/server") == 1; }));
  CHECK(early.wait_for(300ms) == std::future_status::timeout);
  server->on("fast", fast);
  server->start_serving();
  REQUIRE(early.wait_for(5s) == std::future_status::ready);
  auto reply = early.get();
  REQUIRE(reply.has_value());
  CHECK(reply->at("ok") == true);
  CHECK(client->call_sync("test/server", "fast", Json::object(), 5s).has_value());
}

TEST_CASE("an address announced in a withdrawn address's slot ends that address for readers",
          "[control]") {
  auto pp = test::participant();
  std::mutex m;
  std::set<std::string> alive;
  std::vector<std::string> gone;
  control::EndpointOptions options;
  options.on_announcement = [&](const control::AnnouncementEvent &e) {
    std::lock_guard lock(m);
    if (e.kind == control::AnnouncementEvent::Kind::Alive) {
      alive.insert(e.address);
      return;
    }
    alive.erase(e.address);
    gone.push_back(e.address);
  };
  auto watcher = open(pp, "test/watcher", options);
  auto node = open(pp, "test/node1");
  REQUIRE(node->announce("test/node1/p1", "component", Json::object()).has_value());
  REQUIRE(eventually([&] {
    std::lock_guard lock(m);
    return alive.count("test/node1/p1") == 1;
  }));
  // Withdrawn and replaced at once: the reader may see the disposal or only the new address.
  node->withdraw("test/node1/p1");
  REQUIRE(node->announce("test/node1/p2", "component", Json::object()).has_value());
  REQUIRE(eventually([&] {
    std::lock_guard lock(m);
    return alive.count("test/node1/p2") == 1;
  }));
  std::lock_guard lock(m);
  CHECK(alive == std::set<std::string>{"test/node1/p2"});
  CHECK(gone == std::vector<std::string>{"test/node1/p1"});
}

TEST_CASE("CLI clients are answered through one shared writer, each getting its own replies",
          "[control]") {
  auto pp = test::participant();
  auto domain = open(pp, "test/domain");
  domain->on("echo",
             [](const Json &body, const control::RequestContext &) -> control::CallResult<Json> {
               return body;
             });
  std::vector<std::unique_ptr<control::Endpoint>> clients;
  for (int i = 0; i < 3; ++i) {
    auto client = open(pp, fmt::format("test/cli/host-1-{}", i));
    auto reply = client->call_sync("test/domain", "echo", Json{{"n", i}}, 5s);
    REQUIRE(reply.has_value());
    CHECK(reply->at("n") == i);
    clients.push_back(std::move(client));
  }
  CHECK(writers_into(pp, "rsca_ctl_Reply", "test/cli/*") == 1);
  CHECK(writers_into(pp, "rsca_ctl_Reply", "test/cli/host-1-0") == 0);
  clients.clear(); // all gone: the shared way stays
  auto late = open(pp, "test/cli/host-1-9");
  REQUIRE(late->call_sync("test/domain", "echo", Json::object(), 5s).has_value());
  CHECK(writers_into(pp, "rsca_ctl_Reply", "test/cli/*") == 1);
}
