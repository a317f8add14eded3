// JSON text from outside a process, bounded (protocol/json_text.hpp), and what a link makes of a
// frame nested beyond the bound (control/link_socket.hpp): issue 37, defect 2.
#include <catch2/catch.hpp>

#include <string>

#include <sys/socket.h>

#include "common/log_limiter.hpp"
#include "control/link_socket.hpp"
#include "protocol/json_text.hpp"

using namespace rsca;
using protocol::Json;
namespace link_frames = rsca::protocol::link;

namespace {

// `value` inside `depth` arrays: [[[…value…]]].
std::string nested(std::size_t depth, const std::string &value = "1") {
  return std::string(depth, '[') + value + std::string(depth, ']');
}

} // namespace

TEST_CASE("json text: arrays and objects nested up to 64 deep are read, one more is refused "
          "naming the bound",
          "[protocol][json-text]") {
  const auto deepest = protocol::parse_json(nested(protocol::kMaxJsonDepth));
  REQUIRE(deepest.has_value());
  CHECK(deepest->is_array());
  const std::string objects = R"({"a": {"b": [{"c": "[[[[{{{"}]}})";
  CHECK(protocol::parse_json(objects, 4).has_value()); // brackets inside a string do not count
  CHECK_FALSE(protocol::parse_json(objects, 3).has_value());
  CHECK_FALSE(protocol::parse_json(R"({"a": {"b": [1]}})", 2).has_value());

  const auto refused = protocol::parse_json(nested(protocol::kMaxJsonDepth + 1));
  REQUIRE_FALSE(refused.has_value());
  CHECK(refused.error() == "nests deeper than 64 levels");
  const auto escaped = protocol::parse_json(R"(["\"[[[", [[1]]])", 2);
  REQUIRE_FALSE(escaped.has_value()); // an escaped quote does not end the string
  CHECK_THAT(escaped.error(), Catch::Contains("nests deeper"));

  const auto broken = protocol::parse_json(R"({"a": )" + std::string(100000, 'x'));
  REQUIRE_FALSE(broken.has_value());
  CHECK_THAT(broken.error(), Catch::StartsWith("not valid JSON"));
  CHECK(broken.error().size() < 300); // the long token is not quoted whole
}

TEST_CASE("json text: a text nested 100,000 deep is refused without being built, and its "
          "pruned parse keeps what is shallower",
          "[protocol][json-text]") {
  const std::string deep = R"({"id": "7", "body": )" + nested(100000) + "}";
  const auto refused = protocol::parse_json(deep);
  REQUIRE_FALSE(refused.has_value());
  CHECK(protocol::nests_deeper(deep, protocol::kMaxJsonDepth));

  const Json pruned = protocol::parse_json_pruned(deep, 3);
  REQUIRE(pruned.is_object());
  CHECK(pruned.at("id") == "7");
  // body [[[…]]]: its 2 outermost arrays are within the bound of 3, the third and all inside
  // it never built.
  CHECK(pruned.at("body") == Json::parse("[[]]"));
  const Json copy = pruned; // a copy recurses: it is shallow now
  CHECK(copy == pruned);
}

TEST_CASE("node link: a frame nested 100,000 deep is refused and the link lives: a request is "
          "answered bad request, a reply fails its call",
          "[node-link][json-text]") {
  auto [node_end, process_end] = control::make_link_pair().value();
  const int out = process_end.get(); // the process writes, the node reads
  const int in = node_end.get();
  auto send = [&](const std::string &text) {
    const std::string wire = control::wire_of(text);
    std::size_t sent = 0;
    while (sent < wire.size()) {
      const ssize_t n = ::send(out, wire.data() + sent, wire.size() - sent, 0);
      REQUIRE(n > 0);
      sent += static_cast<std::size_t>(n);
    }
  };
  control::FrameReader reader;
  std::vector<link_frames::Frame> frames;
  std::string why;
  // Read until `count` frames or answers are there (the socket holds the frame whole).
  auto read = [&](std::size_t count) {
    std::vector<link_frames::Reply> answers;
    while (frames.size() + answers.size() < count) {
      REQUIRE(reader.read_from(in, frames, why));
      for (auto &a : reader.answers())
        answers.push_back(std::move(a));
    }
    return answers;
  };

  send(R"({"request": {"id": "r1", "target": "t", "operation": "op", "sender": "s",)"
       R"( "timeout_ms": 1000, "body": )" +
       nested(100000) + "}}");
  auto answers = read(1);
  REQUIRE(answers.size() == 1);
  CHECK(answers[0].id == "r1");
  CHECK(answers[0].status == static_cast<std::int32_t>(protocol::Status::BadRequest));
  CHECK_THAT(answers[0].error, Catch::Contains("deeper than 64 levels"));
  CHECK(frames.empty());

  send(R"({"reply": {"id": "c1", "status": 0, "error": "", "body": {"a": )" + nested(100000) +
       "}}}");
  CHECK(read(1).empty());
  REQUIRE(frames.size() == 1);
  const auto &reply = std::get<link_frames::Reply>(frames[0]);
  CHECK(reply.id == "c1");
  CHECK(reply.status == static_cast<std::int32_t>(protocol::Status::BadRequest));
  CHECK_THAT(reply.error, Catch::Contains("deeper than 64 levels"));
  frames.clear();

  // The link reads on.
  send(R"({"withdraw": {"address": "a"}})");
  read(1);
  REQUIRE(frames.size() == 1);
  CHECK(std::get<link_frames::Withdraw>(frames[0]).address == "a");
}

TEST_CASE("log limiter: the first event is said, the rest of the interval counted, and the next "
          "line says how many were held back",
          "[json-text]") {
  LogLimiter limiter(std::chrono::seconds(10));
  const auto start = LogLimiter::Clock::now();
  auto first = limiter.allow(start);
  REQUIRE(first.has_value());
  CHECK(*first == 0);
  for (int i = 0; i < 999; ++i)
    CHECK_FALSE(limiter.allow(start + std::chrono::seconds(5)).has_value());
  auto next = limiter.allow(start + std::chrono::seconds(11));
  REQUIRE(next.has_value());
  CHECK(*next == 999);
  CHECK(LogLimiter::unsaid_note(*next) == " (999 more like it since the last such line)");
  CHECK(LogLimiter::unsaid_note(0).empty());
}
