// The launch as a saga (domain/launch.cpp, domain/saga.hpp): a failure at each step of a launch
// of ProducerConsumer leaves nothing behind — no allocation, no event channel member, every
// process that started terminated, every component forgotten — and says what it undid. The
// control plane is a fake (control::Caller) that answers as nodes and components would, and
// fails the one operation a test names; the allocator, registry and channels are the real ones.
#include <catch2/catch.hpp>

#include <set>

#include "domain/application_factory.hpp"
#include "domain/saga.hpp"
#include "profile/profile_loader.hpp"
#include "protocol/component_ops.hpp"
#include "protocol/exec_params.hpp"
#include "protocol/node_ops.hpp"

using namespace rsca;
// Names, not the namespace: this file shares a translation unit with others (unity build), where
// all of rsca::domain would clash with their names (component::Delivery).
using control::Json;
using rsca::domain::Application;
using rsca::domain::ApplicationFactory;
using rsca::domain::ComponentRegistry;
using rsca::domain::DomainServices;
using rsca::domain::EventChannelManager;
using rsca::domain::LaunchIdentity;
using rsca::domain::LaunchRequest;
using rsca::domain::LaunchStep;
using rsca::domain::Saga;

namespace {

const std::filesystem::path kSdr = std::filesystem::path(RSCA_SOURCE_DIR) / "profiles";
// Events (tests/data/integration): a producer publishing on channel Ticks, two consumers
// subscribed, three processes; ProducerConsumer has no channel.
const std::filesystem::path kIntegrationSdr =
    std::filesystem::path(RSCA_TEST_DATA_DIR) / "integration";

// An application of an SDR root, by name: dom/waveforms/NAME/NAME.sad.xml.
struct AppFile {
  std::filesystem::path sdr = kSdr;
  std::string name = "ProducerConsumer";
};

// Answers every call as the node and the components would, registering each component whose
// process it "starts"; fails every call of `fail_operation` from its `fail_from`th on.
class FakeCaller final : public control::Caller {
public:
  explicit FakeCaller(ComponentRegistry &registry) : registry_(registry) {}

  std::string fail_operation;
  int fail_from = 1;
  std::string unavailable_operation; // its calls fail as to a node that is lost
  bool register_components = true;
  std::vector<control::Call> made;
  std::set<std::int64_t> started, terminated;
  std::set<std::string> forgotten;

  std::vector<control::CallResult<Json>> call_all(const std::vector<control::Call> &calls,
                                                  std::chrono::milliseconds) override {
    std::vector<control::CallResult<Json>> out;
    for (const auto &c : calls) {
      made.push_back(c);
      if (c.operation == fail_operation && ++failures_ >= fail_from) {
        out.emplace_back(tl::unexpect,
                         control::CallError{control::Status::Failed, "injected failure"});
        continue;
      }
      if (c.operation == unavailable_operation) {
        out.emplace_back(tl::unexpect,
                         control::CallError{control::Status::Unavailable, "the node is lost"});
        continue;
      }
      out.push_back(answer(c));
    }
    return out;
  }
  void route(const std::string &, const std::string &) override {}
  void prepare(const std::string &) override {}
  void forget(const std::string &target) override { forgotten.insert(target); }

  std::size_t count(std::string_view operation) const {
    return std::count_if(made.begin(), made.end(),
                         [&](const auto &c) { return c.operation == operation; });
  }

private:
  control::CallResult<Json> answer(const control::Call &c) {
    if (c.operation == protocol::node::Execute::name) {
      const auto request = protocol::decode<protocol::node::ExecuteRequest>(c.body);
      REQUIRE(request.has_value());
      const std::int64_t pid = next_pid_++;
      started.insert(pid);
      if (register_components)
        for (const auto &address : protocol::control_addresses(request->args))
          registry_.announced(address);
      return protocol::encode(protocol::node::ExecuteReply{pid, "/tmp/fake.log"});
    }
    if (c.operation == protocol::node::Terminate::name) {
      const auto pid = c.body.at("pid").get<std::int64_t>();
      terminated.insert(pid);
      return Json{{"pid", pid}};
    }
    if (c.operation == protocol::component::AwaitMatched::name) {
      auto request = protocol::decode<protocol::component::AwaitMatchedRequest>(c.body);
      REQUIRE(request.has_value());
      protocol::component::AwaitMatchedReply reply{true, request->connections};
      for (auto &a : reply.connections)
        a.matched = a.peers;
      return protocol::encode(reply);
    }
    return Json::object();
  }

  ComponentRegistry &registry_;
  int failures_ = 0;
  std::int64_t next_pid_ = 1000;
};

allocator::Device node_gpp(const std::string &node) {
  allocator::Device d;
  d.id = node + ":GPP_1";
  d.node = node;
  d.kind = "gpp";
  d.properties.push_back({"os_name", "os_name", "Linux", profile::Action::Eq});
  d.properties.push_back({"processor_name", "processor_name", "x86_64", profile::Action::Eq});
  d.capacity[allocator::kCpuCapacity] = 400;
  d.capacity[allocator::kMemCapacity] = 4096;
  return d;
}

struct Domain {
  Domain() {
    allocator.set_node_devices("node1", {node_gpp("node1")});
    services.domain_name = "test";
    services.endpoint = &caller;
    services.allocator = &allocator;
    services.components = &registry;
    services.channels = &channels;
    services.node_address = [](const std::string &node) -> std::optional<std::string> {
      return protocol::node_address("test", node);
    };
    services.next_launch = [this] { return LaunchIdentity{1, ++launches}; };
    services.call_timeout = std::chrono::milliseconds(500);
    services.registration_timeout = std::chrono::milliseconds(300);
  }

  control::CallResult<std::shared_ptr<Application>> launch(std::vector<LaunchStep> &steps,
                                                           const AppFile &file = {}) {
    profile::ProfileLoader loader(file.sdr);
    auto app =
        loader.load_application(file.sdr / "dom/waveforms" / file.name / (file.name + ".sad.xml"));
    INFO((app ? std::string() : app.error().to_string()));
    REQUIRE(app.has_value());
    request.name = "PC";
    request.installed = file.name;
    request.profile = std::make_shared<profile::ResolvedApplication>(std::move(*app));
    return ApplicationFactory(services).create(
        request, [&steps](const LaunchStep &step) { steps.push_back(step); });
  }

  // Nothing of the launch is left: no reservation, no channel, every process started was
  // terminated, no component is still known.
  void require_nothing_left() {
    CHECK(allocator.reservations() == 0);
    const auto load = allocator.snapshot().at("node1:GPP_1").load;
    for (const auto &[name, amount] : load.allocated)
      CHECK(amount == Approx(0).margin(1e-9));
    for (const auto &cpu : load.cpu_tasks)
      CHECK(cpu.empty());
    CHECK(channels.list().empty());
    CHECK(caller.terminated == caller.started);
    for (const auto &c : caller.made)
      if (c.operation == protocol::node::Execute::name)
        for (const auto &address : protocol::control_addresses(
                 protocol::decode<protocol::node::ExecuteRequest>(c.body)->args)) {
          CHECK_FALSE(registry.registered(address));
          CHECK(caller.forgotten.count(address) == 1);
        }
  }

  ComponentRegistry registry;
  FakeCaller caller{registry};
  allocator::ResourceAllocator allocator;
  EventChannelManager channels{"test"};
  DomainServices services;
  LaunchRequest request;
  std::uint64_t launches = 0;
};

} // namespace

TEST_CASE("saga: undoes run in reverse, once, and say what they undid", "[saga]") {
  Saga saga;
  std::vector<int> order;
  saga.on_undo([&] {
    order.push_back(1);
    return std::string("first");
  });
  saga.on_undo([&] {
    order.push_back(2);
    return std::string(); // nothing to say
  });
  saga.on_undo([&] {
    order.push_back(3);
    return std::string("third");
  });
  CHECK(saga.roll_back() == std::vector<std::string>{"third", "first"});
  CHECK(order == std::vector<int>{3, 2, 1});
  CHECK(saga.roll_back().empty());
  saga.on_undo([&] { return std::string("kept"); });
  saga.commit();
  CHECK(saga.roll_back().empty());
}

TEST_CASE("launch: a launch that succeeds keeps what it did", "[launch]") {
  Domain d;
  std::vector<LaunchStep> steps;
  auto app = d.launch(steps);
  REQUIRE(app.has_value());
  CHECK(steps.size() == 8);
  CHECK(d.allocator.reservations() == 1);
  CHECK(d.caller.started.size() == 2);
  CHECK(d.caller.terminated.empty());
  CHECK(d.caller.count(protocol::component::Start::name) == 2);
  // Released, it leaves nothing.
  REQUIRE(ApplicationFactory(d.services).release(**app).has_value());
  d.require_nothing_left();
}

TEST_CASE("launch: a failure at any step leaves nothing behind and says what was undone",
          "[launch]") {
  struct Case {
    const char *operation;
    int from;
    const char *step;
    const char *undone; // a part of the "rolled back" report
  };
  const Case cases[] = {
      {"node.execute", 2, "execute", "1 process terminated"},
      {"component.initialize", 1, "initialize", "2 processes terminated"},
      {"component.configure", 1, "configure", "2 processes terminated"},
      {"component.connect", 2, "connect", "allocations on node1:GPP_1 released"},
      {"component.await_matched", 1, "connect", "2 processes terminated"},
      {"component.start", 2, "start", "2 processes terminated"},
  };
  for (const auto &c : cases) {
    DYNAMIC_SECTION(c.operation << " failing at call " << c.from) {
      Domain d;
      d.caller.fail_operation = c.operation;
      d.caller.fail_from = c.from;
      std::vector<LaunchStep> steps;
      auto app = d.launch(steps);
      REQUIRE_FALSE(app.has_value());
      const auto &message = app.error().message;
      CHECK_THAT(message, Catch::Contains(fmt::format("failed at step '{}'", c.step)));
      CHECK_THAT(message, Catch::Contains("injected failure"));
      CHECK_THAT(message, Catch::Contains(c.undone));
      REQUIRE_FALSE(steps.empty());
      CHECK(steps.back().detail == "failed");
      d.require_nothing_left();
    }
  }
}

TEST_CASE("launch: a failure after an application joined its event channel leaves no member of "
          "it",
          "[launch]") {
  const AppFile events{kIntegrationSdr, "Events"};
  {
    Domain d; // launched, its three members are in the channel
    std::vector<LaunchStep> steps;
    auto app = d.launch(steps, events);
    INFO((app ? std::string() : app.error().message));
    REQUIRE(app.has_value());
    const auto channels = d.channels.list();
    REQUIRE(channels.size() == 1);
    CHECK(channels.front().name == "Ticks");
    CHECK(channels.front().members.size() == 3);
  }
  for (const char *operation : {"node.execute", "component.connect", "component.start"}) {
    DYNAMIC_SECTION(operation << " failing") {
      Domain d;
      d.caller.fail_operation = operation;
      std::vector<LaunchStep> steps;
      auto app = d.launch(steps, events);
      REQUIRE_FALSE(app.has_value());
      CHECK_THAT(app.error().message, Catch::Contains("event channels Ticks destroyed"));
      d.require_nothing_left();
    }
  }
}

TEST_CASE("launch: the processes a lost node runs are left to end at its return, and the report "
          "says so, not that they were terminated",
          "[launch]") {
  Domain d;
  d.caller.fail_operation = "component.start";       // the launch fails once its processes run
  d.caller.unavailable_operation = "node.terminate"; // and their node is lost meanwhile
  std::set<std::int64_t> later;
  d.services.end_when_back = [&](const std::string &node, long pid, const std::string &label) {
    CHECK(node == "node1");
    CHECK_THAT(label, Catch::StartsWith("PC/"));
    later.insert(pid);
  };
  std::vector<LaunchStep> steps;
  auto app = d.launch(steps);
  REQUIRE_FALSE(app.has_value());
  CHECK_THAT(app.error().message, Catch::Contains("2 processes to end when their node is back"));
  CHECK_THAT(app.error().message, !Catch::Contains("terminated"));
  CHECK(later == d.caller.started);
  CHECK(d.allocator.reservations() == 0);
  CHECK(d.channels.list().empty());
}

TEST_CASE("launch: components that never register fail the register step, undone", "[launch]") {
  Domain d;
  d.caller.register_components = false;
  std::vector<LaunchStep> steps;
  auto app = d.launch(steps);
  REQUIRE_FALSE(app.has_value());
  CHECK_THAT(app.error().message, Catch::Contains("failed at step 'register'"));
  CHECK_THAT(app.error().message, Catch::Contains("2 processes terminated"));
  d.require_nothing_left();
}

TEST_CASE("launch: an application no device can run fails to allocate, nothing done", "[launch]") {
  Domain d;
  d.allocator.remove_node("node1");
  d.allocator.set_node_devices("node1", {});
  std::vector<LaunchStep> steps;
  auto app = d.launch(steps);
  REQUIRE_FALSE(app.has_value());
  CHECK_THAT(app.error().message, Catch::Contains("failed at step 'allocate'"));
  CHECK(d.caller.made.empty());
  CHECK(d.allocator.reservations() == 0);
  CHECK(d.channels.list().empty());
}
