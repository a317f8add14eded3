// A connection on a TCP stream (transport="tcp", component/tcp_stream.hpp), on loopback: frames
// arrive whole and in order; a stream that does not begin with the connection's token, or sends
// a frame longer than a stream takes, is closed unread; a uses port and a provides port connected
// over it deliver every sample, on the stream's thread when the port asked for the listener's
// delivery, and count each other as matched until the writer goes.
#include <atomic>
#include <chrono>
#include <cstring>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <catch2/catch.hpp>

#include "component/ports.hpp"
#include "component/receive_loop.hpp"
#include "component/tcp_stream.hpp"
#include "dds/port_qos.hpp"
#include "eventually.hpp"

using namespace std::chrono_literals;
using namespace rsca;
using component::detail::TcpReceiver;
using component::detail::TcpSender;

using rsca::test::eventually;

namespace {

constexpr const char *kToken = "0123456789abcdef0123456789abcdef";

struct Frames {
  std::mutex mutex;
  std::vector<std::string> got;
  std::size_t size() {
    std::lock_guard lock(mutex);
    return got.size();
  }
};

std::unique_ptr<TcpReceiver> receiver(Frames &frames) {
  auto r = TcpReceiver::listen("127.0.0.1", kToken, [&frames](const std::byte *at, std::size_t n) {
    std::lock_guard lock(frames.mutex);
    frames.got.emplace_back(reinterpret_cast<const char *>(at), n);
  });
  REQUIRE(r.has_value());
  return std::move(*r);
}

tl::expected<void, std::string> send_text(TcpSender &s, const std::string &text) {
  return s.send(text.size(), [&text](std::byte *at) { std::memcpy(at, text.data(), text.size()); });
}

// A raw socket to the receiver, for what a well-behaved writer never sends.
int raw_connect(const std::string &endpoint) {
  const auto colon = endpoint.rfind(':');
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(std::stoi(endpoint.substr(colon + 1))));
  ::inet_pton(AF_INET, endpoint.substr(0, colon).c_str(), &a.sin_addr);
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  REQUIRE(::connect(fd, reinterpret_cast<sockaddr *>(&a), sizeof a) == 0);
  return fd;
}

void raw_frame(int fd, std::uint32_t length, const std::string &body) {
  REQUIRE(::send(fd, &length, sizeof length, MSG_NOSIGNAL) == sizeof length);
  if (!body.empty())
    REQUIRE(::send(fd, body.data(), body.size(), MSG_NOSIGNAL) ==
            static_cast<ssize_t>(body.size()));
}

} // namespace

TEST_CASE("tcp stream: frames arrive whole and in order, and the writer is counted while connected",
          "[component][tcp]") {
  Frames frames;
  auto r = receiver(frames);
  CHECK(r->writers() == 0);
  auto s = TcpSender::connect(r->endpoint(), kToken, 2s);
  REQUIRE(s.has_value());
  for (int i = 0; i < 200; ++i)
    REQUIRE(send_text(**s, "frame " + std::to_string(i) + std::string(i * 37, 'x')).has_value());
  REQUIRE(eventually([&] { return frames.size() == 200; }));
  for (int i = 0; i < 200; ++i)
    CHECK(frames.got[i] == "frame " + std::to_string(i) + std::string(i * 37, 'x'));
  CHECK(r->writers() == 1);
  CHECK((*s)->readers() == 1);
  s->reset(); // the writer goes
  REQUIRE(eventually([&] { return r->writers() == 0; }));
  CHECK(r->refused() == 0);
}

namespace {

// A good writer is taken after streams that never sent the token, and its frames arrive.
void good_writer_taken(TcpReceiver &r, Frames &frames) {
  auto good = TcpSender::connect(r.endpoint(), kToken, 2s);
  REQUIRE(good.has_value());
  REQUIRE(send_text(**good, "hello").has_value());
  REQUIRE(eventually([&] { return frames.size() == 1; }));
  CHECK(frames.got[0] == "hello");
}

} // namespace

TEST_CASE("tcp stream: a wrong token, no token, or a frame too long closes the stream unread",
          "[component][tcp]") {
  Frames frames;
  auto r = receiver(frames);
  SECTION("a wrong token") {
    auto s = TcpSender::connect(r->endpoint(), "ffffffffffffffffffffffffffffffff", 2s);
    REQUIRE(s.has_value()); // TCP connects; the reader closes it once it reads the token
    REQUIRE(eventually([&] { return r->refused() == 1; }));
    (void)send_text(**s, "not for you");
    CHECK(frames.size() == 0);
    good_writer_taken(*r, frames);
  }
  SECTION("a token of the wrong length") {
    const int fd = raw_connect(r->endpoint());
    raw_frame(fd, 1u << 30, "");
    REQUIRE(eventually([&] { return r->refused() == 1; }));
    ::close(fd);
    CHECK(frames.size() == 0);
    good_writer_taken(*r, frames);
  }
  SECTION("a frame longer than a stream takes, after the right token") {
    const int fd = raw_connect(r->endpoint());
    raw_frame(fd, static_cast<std::uint32_t>(std::strlen(kToken)), kToken);
    REQUIRE(eventually([&] { return r->writers() == 1; }));
    raw_frame(fd, component::detail::kMaxFrame + 1, "");
    REQUIRE(eventually([&] { return r->refused() == 1; }));
    CHECK(eventually([&] { return r->writers() == 0; }));
    ::close(fd);
    // The token was spent by that stream: nobody is taken after it.
    CHECK(frames.size() == 0);
    CHECK(r->spent());
    CHECK_FALSE(TcpSender::connect(r->endpoint(), kToken, 2s).has_value());
  }
}

// The token travels over the control plane in clear: whoever learnt it must not be taken instead
// of the writer, nor after it (the hostile test delivered 200 forged samples once the writer had
// gone).
TEST_CASE("tcp stream: a token admits one writer once, not a second one, nor anyone after it",
          "[component][tcp]") {
  Frames frames;
  auto r = receiver(frames);
  auto writer = TcpSender::connect(r->endpoint(), kToken, 2s);
  REQUIRE(writer.has_value());
  REQUIRE(send_text(**writer, "from the writer").has_value());
  REQUIRE(eventually([&] { return frames.size() == 1; }));
  // A second connection with the same token while the writer is connected: not taken.
  auto second = TcpSender::connect(r->endpoint(), kToken, 2s);
  if (second)
    (void)send_text(**second, "forged while connected");
  writer->reset(); // the writer goes
  REQUIRE(eventually([&] { return r->spent(); }));
  CHECK(r->writers() == 0);
  // After it: refused at once (nobody listens any more), and nothing forged arrives.
  auto after = TcpSender::connect(r->endpoint(), kToken, 2s);
  CHECK_FALSE(after.has_value());
  if (after)
    for (int i = 0; i < 200; ++i)
      (void)send_text(**after, "forged " + std::to_string(i));
  REQUIRE(frames.size() == 1);
  CHECK(frames.got[0] == "from the writer");
}

TEST_CASE("tcp stream: bad endpoints and tokens are refused before anything is opened",
          "[component][tcp]") {
  CHECK_FALSE(TcpSender::connect("127.0.0.1:1", "short", 1s).has_value());
  CHECK_FALSE(TcpSender::connect("not-an-address:80", kToken, 1s).has_value());
  CHECK_FALSE(TcpSender::connect("127.0.0.1:99999", kToken, 1s).has_value());
  CHECK_FALSE(TcpSender::connect("127.0.0.1", kToken, 1s).has_value());
  CHECK_FALSE(TcpReceiver::listen("127.0.0.1", "NOT-HEX-TOKEN", nullptr).has_value());
  CHECK_FALSE(TcpReceiver::listen("localhost", kToken, nullptr).has_value());
}

namespace {

// A uses port and a provides port of this process, connected over a TCP stream on loopback.
struct TcpPair {
  std::recursive_mutex owner_lock;
  std::mutex mutex;
  std::vector<std::uint64_t> sequences;
  std::atomic<std::thread::id> loop_thread{};
  std::vector<bool> on_loop;
  component::ProvidesPort<port::Samples> in;
  component::UsesPort<port::Samples> out{"out"};
  std::unique_ptr<component::detail::ReceiveLoop> loop;

  explicit TcpPair(component::Delivery delivery)
      : in(
            "in",
            [this](const port::Samples &s) {
              std::lock_guard lock(mutex);
              sequences.push_back(s.sequence);
              on_loop.push_back(std::this_thread::get_id() == loop_thread.load());
            },
            delivery) {
    auto started = component::detail::ReceiveLoop::start(
        [this] { in.take_all(loop->delivering()); }, &owner_lock);
    REQUIRE(started.has_value());
    loop = std::move(*started);
    loop_thread = loop->thread().get_id();
    loop->set_delivering(true);
    auto qos = dds::qos_from_json({{"reliability", "reliable"}, {"history", "keepall"}});
    REQUIRE(qos.has_value());
    auto endpoint = in.connect_tcp(loop.get(), "c", qos->get(), "", kToken, 2s);
    REQUIRE(endpoint.has_value());
    CHECK(endpoint->rfind("127.0.0.1:", 0) == 0);
    auto connected = out.connect_tcp(nullptr, "c", qos->get(), *endpoint, kToken, 2s);
    INFO((connected ? std::string() : connected.error().to_string()));
    REQUIRE(connected.has_value());
    REQUIRE(eventually([&] { return in.matched("c").value_or(0) == 1; }));
    CHECK(out.matched("c").value_or(0) == 1);
  }
  ~TcpPair() {
    out.disconnect_all();
    in.disconnect_all();
    loop->stop();
  }
  std::size_t count() {
    std::lock_guard lock(mutex);
    return sequences.size();
  }
};

} // namespace

TEST_CASE("tcp stream: ports deliver every sample in order, on the stream's thread when asked, "
          "and the reader sees its writer go",
          "[component][tcp]") {
  const auto delivery = GENERATE(component::Delivery::Listener, component::Delivery::ReceiveThread);
  INFO("listener delivery " << (delivery == component::Delivery::Listener));
  TcpPair pair(delivery);
  for (std::uint64_t i = 0; i < 100; ++i) {
    port::Samples s;
    s.sequence = i;
    s.samples = {static_cast<double>(i)};
    auto written = pair.out.write(s);
    REQUIRE(written.has_value());
    CHECK(*written == 1);
  }
  REQUIRE(eventually([&] { return pair.count() == 100; }));
  std::lock_guard lock(pair.mutex);
  for (std::uint64_t i = 0; i < 100; ++i)
    CHECK(pair.sequences[i] == i);
  // The receive loop never ran a callback of a port that asked for the stream's thread (nothing
  // held the lock it needs here), and always ran them for one that did not.
  const auto on_loop =
      static_cast<std::size_t>(std::count(pair.on_loop.begin(), pair.on_loop.end(), true));
  CHECK(on_loop == (delivery == component::Delivery::Listener ? 0u : 100u));
  CHECK(pair.in.status().at(0).samples == 100);
  pair.out.disconnect_all();
  CHECK(eventually([&] { return pair.in.matched("c").value_or(1) == 0; }));
}
