// What a hostile test of the built daemons found (issue 37): requests that a client on the
// network, a client on a node's socket or a component on its link could send, sent to the real
// daemons as they would send them, and then the daemons still answer.
#include <sys/socket.h>

#include "../unit/link_peer.hpp"
#include "control.h" // generated from dds/control.idl: requests written raw, as anyone may
#include "control/link_socket.hpp"
#include "domain_fixture.hpp"
#include "protocol/topics.hpp"

using namespace rsca::test;
namespace link_frames = rsca::protocol::link;

namespace {

// `depth` arrays inside one another: 100,000 of them are 200 KB of text.
std::string nested(std::size_t depth) {
  return std::string(depth, '[') + std::string(depth, ']');
}

// A client on the control plane's DDS topics with a participant of its own, writing requests
// raw: a body never parsed on this side, and a reply address of its choosing (read here only
// when asked).
class RawClient {
public:
  explicit RawClient(const std::string &partition) : pp_(participant()) {
    auto qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
    dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
    const char *names[] = {partition.c_str()};
    auto pqos = dds_create_qos();
    dds_qset_partition(pqos, 1, names);
    requests_ = dds_create_topic(pp_->get(), &rsca_ctl_Request_desc, rsca::protocol::kRequestTopic,
                                 qos, nullptr);
    replies_ = dds_create_topic(pp_->get(), &rsca_ctl_Reply_desc, rsca::protocol::kReplyTopic, qos,
                                nullptr);
    writer_ =
        dds_create_writer(dds_create_publisher(pp_->get(), pqos, nullptr), requests_, qos, nullptr);
    qos_ = qos;
    dds_delete_qos(pqos);
    REQUIRE(writer_ > 0);
    REQUIRE(wait_until(
        [&] {
          dds_publication_matched_status_t status{};
          return dds_get_publication_matched_status(writer_, &status) == 0 &&
                 status.current_count > 0;
        },
        20s));
  }
  ~RawClient() { dds_delete_qos(qos_); }

  // Reads the replies into `sender`'s partition from now on.
  void read_replies_to(const std::string &sender) {
    const char *names[] = {sender.c_str()};
    auto pqos = dds_create_qos();
    dds_qset_partition(pqos, 1, names);
    reader_ = dds_create_reader(dds_create_subscriber(pp_->get(), pqos, nullptr), replies_, qos_,
                                nullptr);
    dds_delete_qos(pqos);
    REQUIRE(reader_ > 0);
  }

  void send(const std::string &id, const std::string &sender, const std::string &target,
            const std::string &operation, const std::string &body) {
    rsca_ctl_Request request{};
    request.id = const_cast<char *>(id.c_str());
    request.sender = const_cast<char *>(sender.c_str());
    request.target = const_cast<char *>(target.c_str());
    request.operation = const_cast<char *>(operation.c_str());
    request.body = const_cast<char *>(body.c_str());
    REQUIRE(dds_write(writer_, &request) == 0);
  }

  // The status and error of the reply to `id`, once it comes (within 20 s).
  std::optional<std::pair<Status, std::string>> reply(const std::string &id) {
    std::optional<std::pair<Status, std::string>> found;
    wait_until(
        [&] {
          void *samples[16] = {nullptr};
          dds_sample_info_t infos[16];
          const dds_return_t n = dds_take(reader_, samples, infos, 16, 16);
          for (dds_return_t i = 0; i < n; ++i) {
            const auto *r = static_cast<const rsca_ctl_Reply *>(samples[i]);
            if (infos[i].valid_data && id == r->id)
              found = std::pair{static_cast<Status>(r->status), std::string(r->error)};
          }
          if (n > 0)
            dds_return_loan(reader_, samples, n);
          return found.has_value();
        },
        20s);
    return found;
  }

  // The live writers of replies into partitions that start with `prefix`, as DDS's built-in
  // publication topic shows them.
  int reply_writers_into(const std::string &prefix) {
    const dds_entity_t reader =
        dds_create_reader(pp_->get(), DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
    REQUIRE(reader > 0);
    constexpr int kMost = 4096;
    std::vector<void *> samples(kMost, nullptr);
    std::vector<dds_sample_info_t> infos(kMost);
    const dds_return_t n = dds_read(reader, samples.data(), infos.data(), kMost, kMost);
    int count = 0;
    for (dds_return_t i = 0; i < n; ++i) {
      const auto *w = static_cast<const dds_builtintopic_endpoint_t *>(samples[i]);
      std::uint32_t names = 0;
      char **parts = nullptr;
      if (!infos[i].valid_data || infos[i].instance_state != DDS_IST_ALIVE ||
          std::string(w->topic_name) != rsca::protocol::kReplyTopic ||
          !dds_qget_partition(w->qos, &names, &parts))
        continue;
      for (std::uint32_t k = 0; k < names; ++k) {
        count += std::string_view(parts[k]).starts_with(prefix) ? 1 : 0;
        dds_free(parts[k]);
      }
      dds_free(parts);
    }
    if (n > 0)
      dds_return_loan(reader, samples.data(), n);
    dds_delete(reader);
    return count;
  }

private:
  std::shared_ptr<rsca::dds::Participant> pp_;
  dds_qos_t *qos_ = nullptr;
  dds_entity_t requests_ = 0, replies_ = 0, writer_ = 0, reader_ = 0;
};

// A frame of `text`, written raw (LinkWriter would build the body to write it).
void send_frame(int fd, const std::string &text) {
  const std::string wire = rsca::control::wire_of(text);
  std::size_t sent = 0;
  while (sent < wire.size()) {
    const ssize_t n = ::send(fd, wire.data() + sent, wire.size() - sent, MSG_NOSIGNAL);
    REQUIRE(n > 0);
    sent += static_cast<std::size_t>(n);
  }
}

// Sends `body` raw to the domain as `operation`, from an address of its own, and checks that it
// is refused bad request, saying `saying`, and that the domain answers on.
void refused_raw(TestDomain &domain, const std::string &operation, const std::string &body,
                 const std::string &saying) {
  RawClient client("rsca/domain");
  const std::string sender = fmt::format("hostile/raw-{}", getpid());
  client.read_replies_to(sender);
  client.send("raw#1", sender, "rsca/domain", operation, body);
  const auto reply = client.reply("raw#1");
  REQUIRE(reply.has_value());
  CHECK(reply->first == Status::BadRequest);
  CHECK_THAT(reply->second, Catch::Contains(saying));
  CHECK(domain.call("app.list").has_value());
}

} // namespace

TEST_CASE("a request nested 100,000 deep is refused bad request by the domain, which answers on",
          "[integration][hostile]") {
  TestDomain domain(1);
  refused_raw(domain, "app.configure",
              R"({"app": "x", "properties": {"p": )" + nested(100000) + "}}",
              "nests deeper than 64 levels");
}

TEST_CASE("a frame nested 100,000 deep on a node's control socket is answered bad request, and "
          "the node and the client's link go on",
          "[integration][hostile]") {
  TestDomain domain(1);
  auto fd = rsca::control::connect_link((domain.run_dir() / "node1.sock").string());
  REQUIRE(fd.has_value());
  LinkPeer peer(std::move(*fd));
  send_frame(peer.fd.get(),
             R"({"request": {"id": "n1", "target": "rsca/domain", "operation": "app.list", )"
             R"("sender": "x", "timeout_ms": 5000, "body": )" +
                 nested(100000) + "}}");
  auto refused = std::get<link_frames::Reply>(peer.next());
  CHECK(refused.id == "n1");
  CHECK(refused.status == static_cast<std::int32_t>(Status::BadRequest));
  CHECK_THAT(refused.error, Catch::Contains("deeper than 64 levels"));
  REQUIRE(
      peer.writer
          ->send(link_frames::Request{"n2", "rsca/domain", "app.list", "x", 5000, Json::object()})
          .has_value());
  auto answered = std::get<link_frames::Reply>(peer.next());
  CHECK(answered.id == "n2");
  CHECK(answered.status == 0);
  CHECK(domain.call_node(1, "node.status").has_value());
}

TEST_CASE("requests whose reply address nobody reads hold no handler thread and leave no writer "
          "behind",
          "[integration][hostile]") {
  TestDomain domain(1);
  RawClient client("rsca/domain");
  const std::string prefix = fmt::format("hostile/void-{}/", getpid());
  constexpr int kRequests = 200; // 16 workers held 5 s each: over a minute before the fix
  for (int i = 0; i < kRequests; ++i)
    client.send(fmt::format("void#{}", i), fmt::format("{}{}", prefix, i), "rsca/domain",
                "app.list", "{}");
  // Answered while the replies nobody reads wait: `rsca ls apps` failed for ~40 s.
  auto apps = domain.call("app.list", Json::object(), 5s);
  INFO((apps ? std::string() : apps.error().message));
  CHECK(apps.has_value());
  // Bounded at once, and gone once their replies' time is up.
  CHECK(client.reply_writers_into(prefix) <= 256);
  CHECK(wait_until([&] { return client.reply_writers_into(prefix) == 0; }, 30s, 200ms));
}

TEST_CASE("app.create with assign entries naming no component is refused and names one and so are "
          "500,000 of them and the domain answers on",
          "[integration][hostile]") {
  TestDomain domain(1);
  domain.install("Healthy");
  auto refused = domain.call(
      "app.create", Json{{"application", "Healthy"}, {"assign", {{"NoSuchComponent", "GPP_1"}}}});
  REQUIRE_FALSE(refused.has_value());
  CHECK(refused.error().status == Status::BadRequest);
  CHECK_THAT(refused.error().message, Catch::Contains("NoSuchComponent"));

  Json many = Json::object();
  for (int i = 0; i < 500000; ++i)
    many[fmt::format("c{}", i)] = "d";
  auto huge = domain.call("app.create", Json{{"application", "Healthy"}, {"assign", many}}, 60s);
  REQUIRE_FALSE(huge.has_value());
  CHECK(huge.error().status == Status::BadRequest);
  CHECK_THAT(huge.error().message, Catch::Contains("over the limit of 65536"));
  auto apps = domain.call("app.list");
  REQUIRE(apps.has_value());
  CHECK(apps->at("applications").empty());
}

TEST_CASE("a request body over 16 MiB is refused before it is parsed", "[integration][hostile]") {
  TestDomain domain(1);
  std::string body = R"({"application": "x", "assign": {)";
  for (int i = 0; body.size() <= (16U << 20U); ++i)
    body += fmt::format(R"({}"k{}": "d")", i == 0 ? "" : ",", i);
  body += "}}";
  refused_raw(domain, "app.create", body, "over the limit of 16777216");
}

TEST_CASE("clients that connect to a node's control socket and send nothing are closed in time, "
          "and a CLI then gets its answer over the socket",
          "[integration][hostile]") {
  TestDomain domain(1);
  const std::string socket = (domain.run_dir() / "node1.sock").string();
  std::vector<rsca::process::Fd> idle;
  for (int i = 0; i < 80; ++i)
    if (auto fd = rsca::control::connect_link(socket))
      idle.push_back(std::move(*fd));
  REQUIRE(idle.size() >= 64); // every slot taken
  // With another discovery tag the CLI has no DDS way to the domain: only this socket.
  const ChildProcess::Environment socket_only{{"RSCA_DDS_TAG", "nobody-here"},
                                              {"RSCA_NODE_SOCKET", socket}};
  CHECK(wait_until(
      [&] {
        return domain.cli({"--timeout-ms", "2000", "ls", "nodes"}, socket_only).first == 0;
      },
      30s, 500ms));
  // The node closed the first idle client: its end reads the end of the stream.
  char byte = 0;
  CHECK(::recv(idle.front().get(), &byte, 1, MSG_DONTWAIT) == 0);
  idle.clear();

  // 1,000 clients that connect and close at once, most refused while the node has yet to see
  // the others go: a warning per 10 s with a count, not one per client (~930 lines before).
  for (int i = 0; i < 1000; ++i)
    (void)rsca::control::connect_link(socket);
  const fs::path log = domain.run_dir() / "logs" / "rsca-noded.node1.log";
  auto refusal_lines = [&] {
    std::ifstream in(log);
    int count = 0;
    for (std::string line; std::getline(in, line);)
      count += line.find("connected already") != std::string::npos ? 1 : 0;
    return count;
  };
  REQUIRE(wait_until([&] { return refusal_lines() > 0; }, 10s));
  CHECK(refusal_lines() <= 5);
}

TEST_CASE("a component that sends its node a frame nested 100,000 deep is answered bad request "
          "and the node and the component's link go on",
          "[integration][hostile]") {
  TestDomain domain(1);
  const Json app = domain.create("Chatty");
  // Talker_1 (rsca-test-faulty) writes the frame on its link as it takes deep_frame; the level,
  // set next, shows that the node still relays to it.
  for (const Json &properties : {Json{{"deep_frame", 100000}}, Json{{"level", 2}}}) {
    auto configured =
        domain.call("app.configure",
                    Json{{"app", "Chatty"}, {"component", "Talker_1"}, {"properties", properties}});
    INFO(properties.dump() << ": " << (configured ? std::string() : configured.error().message));
    REQUIRE(configured.has_value());
    CHECK(domain.call_node(1, "node.status").has_value());
  }
  REQUIRE(domain.call("app.release", Json{{"app", "Chatty"}}).has_value());
  domain.require_clean(pids_of(app));
}
