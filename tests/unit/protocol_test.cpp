// The wire contracts (core_framework/protocol/): messages round-trip, a malformed request is a
// clear bad request naming the field, addresses and exec parameters are made and read back.
#include <catch2/catch.hpp>

#include "control/operation.hpp"
#include "protocol/addresses.hpp"
#include "protocol/application_ops.hpp"
#include "protocol/component_ops.hpp"
#include "protocol/connection_ops.hpp"
#include "protocol/domain_ops.hpp"
#include "protocol/exec_params.hpp"
#include "protocol/node_ops.hpp"
#include "protocol/topics.hpp"

using namespace rsca;
using protocol::Json;

namespace {

template <typename M>
M round_trip(const M &message) {
  auto decoded = protocol::decode<M>(protocol::encode(message));
  REQUIRE(decoded.has_value());
  return *decoded;
}

} // namespace

TEST_CASE("protocol: a connect request round-trips, its empty optionals left out", "[protocol]") {
  protocol::component::ConnectRequest r;
  r.connection = "samples";
  r.port = "samples_out";
  r.direction = "uses";
  r.repid = "IDL:rsca/Samples:1.0";
  r.topic = "rsca_d_app_1_2_samples";
  r.qos = Json{{"reliability", "reliable"}};
  r.local = true;
  const Json encoded = protocol::encode(r);
  CHECK_FALSE(encoded.contains("filter"));
  CHECK_FALSE(encoded.contains("target"));
  const auto back = round_trip(r);
  CHECK(back.connection == "samples");
  CHECK(back.topic == r.topic);
  CHECK(back.qos == r.qos);
  CHECK(back.local == std::optional<bool>(true));
  CHECK_FALSE(back.filter.has_value());
}

TEST_CASE("protocol: nested messages round-trip", "[protocol]") {
  protocol::node::StatusReply status{"node1",
                                     42,
                                     "robot",
                                     {},
                                     {{7, "app/C_1", "/tmp/c.log"}},
                                     protocol::node::SharedMemoryStatus{1, 2, 3, 4096},
                                     protocol::node::PackageCacheStatus{2, 100, 1000, 1, 50, 3}};
  protocol::node::DeviceRecord gpp{
      "node1:GPP_1",  "GPP_1",        "GPP",          "gpp", Json{{"os_name", "Linux"}},
      Json::object(), Json::object(), Json::object(), "",    {}};
  protocol::node::DeviceRecord sensor = gpp;
  sensor.id = "node1:IR_1";
  sensor.address = "d/device/node1/IR_1";
  sensor.ports = {{"range_out", "uses", "IDL:Range:1.0"}};
  status.devices = {gpp, sensor};
  const auto back = round_trip(status);
  REQUIRE(back.devices.size() == 2);
  CHECK(back.devices[0].properties.at("os_name") == "Linux");
  CHECK(back.devices[1].ports.at(0).repid == "IDL:Range:1.0");
  REQUIRE(back.shared_memory.has_value());
  CHECK(back.shared_memory->ends == 2);
  CHECK(back.shared_memory->bytes == 4096);
  REQUIRE(back.processes.size() == 1);
  CHECK(back.processes[0].pid == 7);
  REQUIRE(back.cache.has_value());
  CHECK(back.cache->fetched_bytes == 50);
  CHECK(back.cache->reused == 3);
}

TEST_CASE("protocol: a component's announcement round-trips, and one without its pid is refused",
          "[protocol]") {
  const protocol::component::Announcement a{
      "C_1",      "C", "app", 42, "initialized", {{"samples_out", "uses", "IDL:rsca/Samples:1.0"}},
      "d/node/n1"};
  const auto back = round_trip(a);
  CHECK(back.id == "C_1");
  CHECK(back.pid == 42);
  CHECK(back.state == "initialized");
  CHECK(back.via == std::optional<std::string>("d/node/n1"));
  REQUIRE(back.ports.size() == 1);
  CHECK(back.ports[0].direction == "uses");

  Json without_pid = protocol::encode(a);
  without_pid.erase("pid");
  const auto refused = protocol::decode<protocol::component::Announcement>(without_pid);
  REQUIRE_FALSE(refused.has_value());
  CHECK_THAT(refused.error(), Catch::Contains("pid"));
}

TEST_CASE("protocol: a malformed message names the field and what is wrong", "[protocol]") {
  using protocol::decode;
  using protocol::node::ExecuteRequest;
  const Json good{{"application", "a"}, {"component", "c"}, {"entrypoint", "e"}, {"args", {"X"}}};
  REQUIRE(decode<ExecuteRequest>(good).has_value());

  Json missing = good;
  missing.erase("entrypoint");
  CHECK(decode<ExecuteRequest>(missing).error() == "missing field \"entrypoint\"");

  Json unknown = good;
  unknown["entry_point"] = "typo";
  CHECK(decode<ExecuteRequest>(unknown).error() == "unknown field \"entry_point\"");

  Json wrong = good;
  wrong["args"] = {"X", 3};
  CHECK(decode<ExecuteRequest>(wrong).error() ==
        "field \"args[1]\": expected a string, found number");

  CHECK(decode<ExecuteRequest>(Json::array()).error() == "expected an object, found array");

  // The caller's budget: a day at most, never negative.
  Json budget = good;
  budget["budget_ms"] = ExecuteRequest::kMaxBudgetMs;
  CHECK(decode<ExecuteRequest>(budget).has_value());
  for (const std::int64_t out : {std::int64_t{-1}, ExecuteRequest::kMaxBudgetMs + 1}) {
    budget["budget_ms"] = out;
    CHECK(decode<ExecuteRequest>(budget).error() == "field \"budget_ms\": out of range");
  }

  using protocol::component::AwaitMatchedRequest;
  const Json nested{{"connections", {{{"port", "p"}, {"connection", 5}}}}};
  CHECK(decode<AwaitMatchedRequest>(nested).error() ==
        "field \"connections[0].connection\": expected a string, found number");
}

TEST_CASE("protocol: integers out of range and of the wrong sign are refused", "[protocol]") {
  using protocol::component::AwaitMatchedRequest;
  Json awaited{{"connections", {{{"port", "p"}, {"connection", "c"}, {"peers", 1}}}}};
  REQUIRE(protocol::decode<AwaitMatchedRequest>(awaited).has_value());
  awaited["connections"][0]["peers"] = 5'000'000'000LL; // an int32
  CHECK(protocol::decode<AwaitMatchedRequest>(awaited).error() ==
        "field \"connections[0].peers\": 5000000000 is out of range");
  awaited["connections"][0]["peers"] = 1.5;
  CHECK(protocol::decode<AwaitMatchedRequest>(awaited).error() ==
        "field \"connections[0].peers\": expected an integer, found number");
  Json status{{"state", "Started"},
              {"ports",
               {{{"name", "p"},
                 {"direction", "uses"},
                 {"connections", {{{"connection", "c"}, {"samples", -1}}}}}}}};
  CHECK(protocol::decode<protocol::component::StatusReply>(status).error() ==
        "field \"ports[0].connections[0].samples\": -1 is out of range");
}

TEST_CASE("protocol: a typed handler answers a malformed request with bad request", "[protocol]") {
  int ran = 0;
  auto handler = control::typed_handler<protocol::node::Terminate>(
      [&ran](const protocol::node::TerminateRequest &r, const control::RequestContext &)
          -> control::CallResult<protocol::node::TerminateReply> {
        ++ran;
        return protocol::node::TerminateReply{r.pid};
      });
  const control::RequestContext context;
  auto bad = handler(Json{{"pid", "12"}}, context);
  REQUIRE_FALSE(bad.has_value());
  CHECK(bad.error().status == control::Status::BadRequest);
  CHECK(bad.error().message == "node.terminate: field \"pid\": expected an integer, found string");
  CHECK(ran == 0);
  auto good = handler(Json{{"pid", 12}}, context);
  REQUIRE(good.has_value());
  CHECK(*good == Json{{"pid", 12}});
  CHECK(ran == 1);
}

TEST_CASE("protocol: a reply that does not fit its contract fails the call", "[protocol]") {
  auto reply = control::reply_of<protocol::node::Execute>(Json{{"pid", 3}});
  REQUIRE_FALSE(reply.has_value());
  CHECK(reply.error().status == control::Status::Failed);
  CHECK(reply.error().message == "malformed reply to node.execute: missing field \"log\"");
  auto failed = control::reply_of<protocol::node::Execute>(
      control::call_error(control::Status::NotFound, "no such device"));
  REQUIRE_FALSE(failed.has_value());
  CHECK(failed.error().status == control::Status::NotFound);
}

TEST_CASE("protocol: a launch request reads as the CLI sends it, and says what it leaves out",
          "[protocol]") {
  using protocol::application::CreateRequest;
  const Json sent{{"application", "PC"},
                  {"start", false},
                  {"assign", {{"Producer_1", "node1:GPP_1"}}},
                  {"launch_id", "42-7"},
                  {"strategy", "spread"}};
  auto request = protocol::decode<CreateRequest>(sent);
  REQUIRE(request.has_value());
  CHECK(request->application == "PC"); // a field of the plan request it extends
  CHECK(request->assign.at("Producer_1") == "node1:GPP_1");
  CHECK(request->strategy == std::optional<std::string>("spread"));
  CHECK(request->launch_id == std::optional<std::string>("42-7"));
  CHECK_FALSE(request->start);
  CHECK_FALSE(request->name.has_value());
  CHECK(protocol::encode(*request) == sent);

  auto least = protocol::decode<CreateRequest>(Json{{"application", "PC"}});
  REQUIRE(least.has_value());
  CHECK(least->start); // started unless asked not to
  CHECK(least->assign.empty());
  CHECK_FALSE(least->strategy.has_value());
}

TEST_CASE("protocol: a malformed application request names its field", "[protocol]") {
  using protocol::decode;
  namespace app = protocol::application;
  const Json create{{"application", "PC"}, {"start", true}};
  REQUIRE(decode<app::CreateRequest>(create).has_value());
  Json typo = create;
  typo["strat"] = "spread";
  CHECK(decode<app::CreateRequest>(typo).error() == "unknown field \"strat\"");
  Json start = create;
  start["start"] = "yes";
  CHECK(decode<app::CreateRequest>(start).error() ==
        "field \"start\": expected true or false, found string");
  Json assign = create;
  assign["assign"] = {{"Producer_1", 3}};
  CHECK(decode<app::CreateRequest>(assign).error() ==
        "field \"assign[\"Producer_1\"]\": expected a string, found number");
  CHECK(decode<app::CreateRequest>(Json{{"name", "x"}}).error() == "missing field \"application\"");
  CHECK(decode<app::AppRequest>(Json{{"application", "PC"}}).error() == "missing field \"app\"");
  CHECK(decode<app::QueryRequest>(Json{{"app", "PC"}, {"ids", "rate_hz"}}).error() ==
        "field \"ids\": expected an array, found string");
  CHECK(decode<app::ConfigureRequest>(Json{{"device", "n:D"}, {"values", {1, 2}}}).error() ==
        "field \"values\": expected an object, found array");
}

TEST_CASE("protocol: configure and query requests name their target", "[protocol]") {
  namespace app = protocol::application;
  auto configure = protocol::decode<app::ConfigureRequest>(
      Json{{"app", "RangeStop"}, {"component", ""}, {"values", {{"speed", "0.4"}, {"on", true}}}});
  REQUIRE(configure.has_value());
  CHECK(configure->app == std::optional<std::string>("RangeStop"));
  CHECK(configure->component == std::optional<std::string>(""));
  CHECK_FALSE(configure->device.has_value());
  REQUIRE(configure->values.has_value());
  CHECK(configure->values->at("speed") == "0.4");
  CHECK(configure->values->at("on") == true); // not text: the domain takes its JSON
  CHECK_FALSE(configure->properties.has_value());

  auto query = protocol::decode<app::QueryRequest>(Json{{"device", "robot:IR_1"}});
  REQUIRE(query.has_value());
  CHECK(query->device == std::optional<std::string>("robot:IR_1"));
  CHECK(query->ids.empty()); // every property
}

TEST_CASE("protocol: a launched application's reply round-trips with its launch", "[protocol]") {
  protocol::application::CreateReply reply;
  reply.name = "PC";
  reply.installed = "ProducerConsumer";
  reply.sad = "dom/waveforms/PC/PC.sad.xml";
  reply.state = "degraded";
  reply.exited = {"Producer_1"};
  protocol::application::ComponentView producer;
  producer.id = "Producer_1";
  producer.pid = 12;
  producer.state = protocol::application::ComponentState::Exited;
  reply.components = {producer};
  reply.launch = {{{"check", "2 components", 0.5}, {"execute", "failed", 12.25}}, 13.0};
  const Json encoded = protocol::encode(reply);
  CHECK(encoded.at("launch").at("steps")[1].at("detail") == "failed");
  CHECK(encoded.at("connections") == Json::array());
  CHECK(encoded.at("components")[0].at("state") == "exited");
  CHECK_FALSE(encoded.at("components")[0].contains("schedule")); // only a periodic one has one
  const auto back = round_trip(reply);
  CHECK(back.name == "PC");
  CHECK(back.exited == std::vector<std::string>{"Producer_1"});
  CHECK(back.components[0].pid == 12);
  CHECK(back.components[0].state == protocol::application::ComponentState::Exited);
  REQUIRE(back.launch.steps.size() == 2);
  CHECK(back.launch.steps[1].ms == 12.25);
  CHECK(back.launch.ms == 13.0);
  Json no_launch = encoded;
  no_launch.erase("launch");
  CHECK(protocol::decode<protocol::application::CreateReply>(no_launch).error() ==
        "missing field \"launch\"");
}

TEST_CASE("protocol: app.show's connections round-trip with their typed ends, channel and live "
          "state, and a reply without them still decodes",
          "[protocol]") {
  namespace app = protocol::application;
  using protocol::connection::ConnectionState;
  using protocol::connection::PortEnd;
  app::ApplicationView view;
  view.name = "Events";
  app::SadConnectionView publish;
  publish.id = "publish";
  publish.uses = "Producer_1.events_out";
  publish.uses_end = PortEnd{"Events", "Producer_1", std::nullopt, "events_out"};
  publish.channel = "Ticks";
  publish.state = ConnectionState::Failed;
  app::SadConnectionView ranges;
  ranges.id = "ranges";
  ranges.uses_end = PortEnd{std::nullopt, std::nullopt, "robot:IRSensor_1", "out"};
  view.connections = {publish, ranges};
  view.external_ports = {{"tap", "Producer_1", "events_out", "uses"}};
  const Json encoded = protocol::encode(view);
  CHECK(encoded.at("connections")[0].at("state") == "failed");
  CHECK(encoded.at("connections")[0].at("channel") == "Ticks");
  CHECK_FALSE(encoded.at("connections")[0].contains("provides_end")); // the channel's side
  CHECK_FALSE(encoded.at("connections")[1].contains("state"));        // an end did not answer
  const auto back = round_trip(view);
  REQUIRE(back.connections.size() == 2);
  CHECK(back.connections[0].uses_end->component == std::optional<std::string>("Producer_1"));
  CHECK(back.connections[0].state == std::optional<ConnectionState>(ConnectionState::Failed));
  CHECK(back.connections[1].uses_end->device == std::optional<std::string>("robot:IRSensor_1"));
  CHECK_FALSE(back.connections[1].channel.has_value());
  REQUIRE(back.external_ports.size() == 1);
  CHECK(back.external_ports[0].kind == "uses");

  Json before = encoded; // as a domain before these fields answered
  before.erase("external_ports");
  for (auto &c : before.at("connections"))
    for (const char *key : {"uses_end", "provides_end", "channel", "filter", "state"})
      c.erase(key);
  const auto old = protocol::decode<app::ApplicationView>(before);
  REQUIRE(old.has_value());
  CHECK(old->external_ports.empty());
  CHECK_FALSE(old->connections[0].state.has_value());
}

TEST_CASE("protocol: launch progress, cancel and plan replies keep what is absent absent",
          "[protocol]") {
  namespace app = protocol::application;
  const Json finished{{"cancelled", false}, {"done", true}};
  auto cancel = protocol::decode<app::CancelReply>(finished);
  REQUIRE(cancel.has_value());
  CHECK_FALSE(cancel->begun.has_value());
  CHECK(protocol::encode(*cancel) == finished);
  CHECK(round_trip(app::CancelReply{true, false, false}).begun == std::optional<bool>(false));

  const Json rejected{{"admitted", false},
                      {"strategy", "pack"},
                      {"rejections", {{{"component", "Greedy_1"}, {"reasons", {"no room"}}}}}};
  auto plan = protocol::decode<app::PlanReply>(rejected);
  REQUIRE(plan.has_value());
  CHECK_FALSE(plan->admitted);
  CHECK_FALSE(plan->plan.has_value());
  CHECK(plan->rejections->at(0).at("component") == "Greedy_1");
  CHECK(protocol::encode(*plan) == rejected);

  auto progress =
      protocol::decode<app::ProgressReply>(Json{{"steps", {{{"step", "check"}}}}, {"done", false}});
  REQUIRE_FALSE(progress.has_value());
  CHECK(progress.error() == "field \"steps[0]\": missing field \"detail\"");
}

TEST_CASE("protocol: a connection request reads its ends, and refuses an end with no port",
          "[protocol]") {
  using protocol::connection::CreateRequest;
  const Json sent{{"uses", {{"application", "pc"}, {"component", "Producer_1"}, {"port", "out"}}},
                  {"provides", {{"device", "monitor:HostMonitor_1"}, {"port", "in"}}},
                  {"qos", {{"depth", 4}}}};
  auto request = protocol::decode<CreateRequest>(sent);
  REQUIRE(request.has_value());
  CHECK(request->uses.component == std::optional<std::string>("Producer_1"));
  CHECK_FALSE(request->uses.device.has_value());
  CHECK(request->provides.device == std::optional<std::string>("monitor:HostMonitor_1"));
  CHECK(request->provides.port == "in");
  CHECK_FALSE(request->id.has_value());
  CHECK(request->qos.at("depth") == 4);
  CHECK(protocol::encode(*request) == sent); // what the domain keeps to restore it

  Json no_port = sent;
  no_port["uses"].erase("port");
  CHECK(protocol::decode<CreateRequest>(no_port).error() ==
        "field \"uses\": missing field \"port\"");
  Json extra = sent;
  extra["provides"]["node"] = "monitor";
  CHECK(protocol::decode<CreateRequest>(extra).error() ==
        "field \"provides\": unknown field \"node\"");
}

TEST_CASE("protocol: a listed connection keeps a null end state null, and its state by name",
          "[protocol]") {
  using protocol::connection::ConnectionState;
  using protocol::connection::ListedConnection;
  ListedConnection pending;
  pending.id = "runtime_1";
  pending.uses = "pc/Producer_1.out";
  pending.application = "(runtime)";
  pending.state = ConnectionState::Pending;
  pending.waiting_for = "application pc";
  const Json encoded = protocol::encode(pending);
  REQUIRE(encoded.contains("uses_state"));
  CHECK(encoded.at("uses_state").is_null());
  CHECK(encoded.at("state") == "pending");
  CHECK_FALSE(encoded.contains("filter"));
  const auto back = round_trip(pending);
  CHECK(back.state == std::optional<ConnectionState>(ConnectionState::Pending));
  CHECK(back.waiting_for == pending.waiting_for);
  CHECK(back.provides_state.is_null());

  Json unknown_state = encoded;
  unknown_state["state"] = "matched";
  CHECK(protocol::decode<ListedConnection>(unknown_state).error() ==
        "field \"state\": \"matched\" is not one of the names allowed");
}

TEST_CASE("protocol: domain replies round-trip, and an install names its broken file",
          "[protocol]") {
  namespace dom = protocol::domain;
  const auto nodes = round_trip(dom::NodesReply{{{"node1", "rsca/node/node1", 77, 3, std::nullopt}},
                                                {{"rsca/node/rogue", "missing field \"host\""}},
                                                {}});
  REQUIRE(nodes.nodes.size() == 1);
  REQUIRE(nodes.refused.size() == 1);
  CHECK(nodes.refused[0].why == "missing field \"host\"");
  CHECK(nodes.nodes[0].pid == 77);
  CHECK(nodes.nodes[0].devices == 3u);
  const auto channel = round_trip(protocol::connection::ChannelView{
      "ticks", "rsca_d_ch_ticks", "", true, 1, 0, {{"publisher", "a", "c", "T_1", "out", ""}}});
  CHECK(channel.operator_owned);
  CHECK(protocol::encode(channel).at("operator") == true);
  CHECK(channel.members.at(0).component == "T_1");

  const Json install{
      {"sad", "dom/a.sad.xml"},
      {"files", {{{"path", "dom/a.sad.xml"}, {"content", "<x/>"}}, {{"path", "b"}}}}};
  CHECK(protocol::decode<dom::InstallRequest>(install).error() ==
        "field \"files[1]\": missing field \"content\"");
}

TEST_CASE("protocol: the domain's typed handler refuses an application request with an unknown "
          "field by name",
          "[protocol]") {
  int ran = 0;
  auto handler = control::typed_handler<protocol::application::Show>(
      [&ran](const protocol::application::AppRequest &, const control::RequestContext &)
          -> control::CallResult<protocol::application::ApplicationView> {
        ++ran;
        return protocol::application::ApplicationView{};
      });
  auto bad = handler(Json{{"app", "PC"}, {"verbose", true}}, control::RequestContext{});
  REQUIRE_FALSE(bad.has_value());
  CHECK(bad.error().status == control::Status::BadRequest);
  CHECK(bad.error().message == "app.show: unknown field \"verbose\"");
  CHECK(ran == 0);
}

TEST_CASE("protocol: addresses are made in one scheme and read back", "[protocol]") {
  const protocol::LaunchIdentity launch{7, 12};
  CHECK(protocol::domain_address("rsca") == "rsca/domain");
  CHECK(protocol::node_address("rsca", "node1") == "rsca/node/node1");
  CHECK(protocol::device_address("rsca", "robot", "IRSensor_1") == "rsca/device/robot/IRSensor_1");
  const auto component = protocol::component_address("rsca", "rh.FM.demo", launch, "X_1");
  CHECK(component == "rsca/component/rh.FM.demo.7.12/X_1");
  CHECK(protocol::incarnation_of(component) == 7u);
  const auto host = protocol::host_address("rsca", "PC", {9, 1}, "node1:GPP_1");
  CHECK(host == "rsca/host/PC.9.1/node1:GPP_1");
  CHECK(protocol::incarnation_of(host) == 9u);
  CHECK_FALSE(protocol::incarnation_of(protocol::node_address("rsca", "n")).has_value());
  CHECK(protocol::cli_address("rsca", "robot", 100, 2) == "rsca/cli/robot-100-2");
}

TEST_CASE("protocol: topic names keep only letters and digits of what users name", "[protocol]") {
  CHECK(protocol::connection_topic("my-domain", "rh.FM", {3, 4}, "conn 1") ==
        "rsca_my_domain_rh_FM_3_4_conn_1");
  CHECK(protocol::runtime_connection_topic("rsca", "runtime_1") == "rsca_rsca_runtime_runtime_1");
  CHECK(protocol::channel_topic("rsca", "ev/chan") == "rsca_rsca_channel_ev_chan");
  CHECK(protocol::domain_events_topic("rsca") == "rsca_rsca_domain_events");
}

namespace {

tl::expected<protocol::ExecParams, std::string> parse(const std::vector<std::string> &args) {
  std::vector<const char *> argv{"component"};
  for (const auto &a : args)
    argv.push_back(a.c_str());
  return protocol::parse_exec_params(static_cast<int>(argv.size()), argv.data());
}

} // namespace

TEST_CASE("protocol: exec parameters are read back as they were made", "[protocol]") {
  protocol::ExecParams p;
  p.identifier = "Producer_1";
  p.name_binding = "Producer";
  p.profile = "/sdr/Producer.spd.xml";
  p.domain = "rsca";
  p.application = "PC";
  p.control_address = "rsca/component/PC.1.1/Producer_1";
  p.schedule = protocol::Schedule{1, 80, std::chrono::milliseconds(10),
                                  std::chrono::milliseconds(2), std::chrono::milliseconds(10)};
  p.others = {{"rate_hz", "20"}};
  p.dds = protocol::kJoinDds;
  auto back = parse(protocol::to_args(p));
  REQUIRE(back.has_value());
  CHECK(back->dds == protocol::kJoinDds);
  CHECK(back->identifier == p.identifier);
  CHECK(back->name_binding == p.name_binding);
  CHECK(back->control_address == p.control_address);
  REQUIRE(back->schedule.has_value());
  CHECK(back->schedule->priority == 80);
  CHECK(back->schedule->budget == std::chrono::milliseconds(2));
  CHECK(back->others == p.others);

  CHECK(parse({"COMPONENT_IDENTIFIER", "a", "PROFILE_NAME"}).error() ==
        "exec parameters come in pairs: \"PROFILE_NAME\" has no value");
  CHECK(parse({"COMPONENT_IDENTIFIER", "a", "PROFILE_NAME", "p"}).error() ==
        "the exec parameter CONTROL_ADDRESS is missing");
  CHECK(parse({"COMPONENT_IDENTIFIER", "a", "PROFILE_NAME", "p", "CONTROL_ADDRESS", "c", "RSCA_CPU",
               "one"})
            .error() == "the exec parameter RSCA_CPU is not a number: \"one\"");
}

TEST_CASE("protocol: a host's exec parameters are read back, and its addresses found",
          "[protocol]") {
  protocol::HostParams host{"rsca/host/PC.1.1/node1:GPP_1", {}};
  for (const char *id : {"A_1", "B_1"}) {
    protocol::ExecParams p;
    p.identifier = id;
    p.profile = std::string("/sdr/") + id + ".spd.xml";
    p.control_address = std::string("rsca/component/PC.1.1/") + id;
    p.library = std::string("lib") + id + ".so";
    host.components.push_back(p);
  }
  const auto args = protocol::to_args(host);
  std::vector<const char *> argv{"rsca-component-host"};
  for (const auto &a : args)
    argv.push_back(a.c_str());
  auto back = protocol::parse_host_params(static_cast<int>(argv.size()), argv.data());
  REQUIRE(back.has_value());
  CHECK(back->control_address == host.control_address);
  REQUIRE(back->components.size() == 2);
  CHECK(back->components[1].library == "libB_1.so");
  CHECK(back->components[1].name_binding == "B_1"); // the identifier when not given
  CHECK(protocol::control_addresses(args) == std::vector<std::string>{host.control_address,
                                                                      "rsca/component/PC.1.1/A_1",
                                                                      "rsca/component/PC.1.1/B_1"});
}
