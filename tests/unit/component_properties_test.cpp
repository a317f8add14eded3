// The component runtime without processes: property bindings against a PRF, configure and query,
// exec parameters and the repid mapping.
#include <atomic>

#include <catch2/catch.hpp>

#include "component/component.hpp"
#include "component/runtime.hpp"

using namespace rsca;
using namespace rsca::component;
using Json = nlohmann::json;
using profile::Scalar;
using profile::SimpleType;

namespace {

profile::SimpleProperty simple_property(std::string id, SimpleType type,
                                        std::optional<Scalar> value = {}) {
  profile::SimpleProperty p;
  p.id = std::move(id);
  p.type = {type, false};
  p.value = std::move(value);
  p.kinds = {profile::PropertyKind::Property};
  return p;
}

struct Stream {
  std::string id;
  double rate = 0;
  std::vector<float> taps;
};

std::vector<Field<Stream>> stream_fields() {
  return {{"stream_id", &Stream::id}, {"sample_rate", &Stream::rate}, {"taps", &Stream::taps}};
}

profile::StructProperty stream_definition() {
  profile::StructProperty s;
  s.id = "stream";
  s.kinds = {profile::PropertyKind::Property};
  s.members.emplace_back(
      simple_property("stream_id", SimpleType::String, Scalar(std::string("s0"))));
  s.members.emplace_back(simple_property("sample_rate", SimpleType::Double));
  profile::SimpleSequenceProperty taps;
  taps.id = "taps";
  taps.type = {SimpleType::Float, false};
  s.members.emplace_back(taps);
  s.value =
      profile::StructValue{{{"stream_id", Scalar(std::string("s0"))}}}; // as the reader sets it
  return s;
}

// A PRF like a component's: read-write, read-only, write-only, allocation-only and unbound ones.
std::vector<profile::PropertyDefinition> definitions() {
  auto rate = simple_property("rate_hz", SimpleType::Double, Scalar(100.0));
  rate.range = profile::ValueRange{Scalar(0.1), Scalar(1000.0)};
  auto count = simple_property("count", SimpleType::ULongLong, Scalar(std::uint64_t{0}));
  count.mode = profile::AccessMode::ReadOnly;
  auto secret = simple_property("secret", SimpleType::String);
  secret.mode = profile::AccessMode::WriteOnly;
  auto capacity = simple_property("capacity", SimpleType::Long);
  capacity.kinds = {profile::PropertyKind::Allocation};
  auto mode = simple_property("mode", SimpleType::Short, Scalar(std::int16_t{0}));
  mode.enumerations = {{"off", Scalar(std::int16_t{0})}, {"on", Scalar(std::int16_t{1})}};
  profile::SimpleSequenceProperty gains;
  gains.id = "gains";
  gains.type = {SimpleType::Long, false};
  gains.values = std::vector<Scalar>{Scalar(std::int32_t{1}), Scalar(std::int32_t{2})};
  return {rate,
          count,
          secret,
          capacity,
          mode,
          gains,
          stream_definition(),
          simple_property("label", SimpleType::String, Scalar(std::string("none")))};
}

// Variables bound to definitions(); "label" stays unbound.
struct Bound {
  double rate = 0;
  std::atomic<std::uint64_t> count{7};
  std::string secret;
  std::int32_t capacity = 0;
  std::int16_t mode = 5;
  std::vector<std::int32_t> gains;
  Stream stream;
  std::vector<std::pair<double, double>> rate_changes;

  PropertySet properties() {
    PropertySet set;
    set.bind("rate_hz", std::make_unique<detail::ScalarBinding<double>>(
                            rate, [this](const double &old_value, const double &new_value) {
                              rate_changes.emplace_back(old_value, new_value);
                            }));
    set.bind("count", std::make_unique<detail::AtomicBinding<std::uint64_t>>(count, nullptr));
    set.bind("secret", std::make_unique<detail::ScalarBinding<std::string>>(secret, nullptr));
    set.bind("capacity", std::make_unique<detail::ScalarBinding<std::int32_t>>(capacity, nullptr));
    set.bind("mode", std::make_unique<detail::ScalarBinding<std::int16_t>>(mode, nullptr));
    set.bind("gains", std::make_unique<detail::SequenceBinding<std::int32_t>>(gains, nullptr));
    set.bind("stream",
             std::make_unique<detail::StructBinding<Stream>>(stream, stream_fields(), nullptr));
    return set;
  }
};

std::string configure_error(control::CallResult<std::vector<std::function<void()>>> result) {
  REQUIRE_FALSE(result.has_value());
  CHECK(result.error().status == control::Status::BadRequest);
  return result.error().message;
}

// A component declaring every kind of binding and a port of each direction: it must compile and
// construct without DDS.
class Declarations final : public Component {
public:
  explicit Declarations(const Context &context) : Component(context) {
    property("rate_hz", rate_, [](const double &, const double &) {});
    property("count", count_);
    property("gains", gains_);
    struct_property("stream", stream_, stream_fields());
    struct_sequence_property("streams", streams_, stream_fields());
    uses_port<port::Command>("commands_out");
    provides_port<port::PropertyEvent>("events_in", [](const port::PropertyEvent &) {});
  }

private:
  double rate_ = 0;
  std::atomic<std::uint64_t> count_{0};
  std::vector<std::int32_t> gains_;
  Stream stream_;
  std::vector<Stream> streams_;
};

} // namespace

TEST_CASE("loading the PRF gives bound variables their defaults", "[component]") {
  Bound b;
  auto set = b.properties();
  REQUIRE(set.load(definitions()).has_value());
  CHECK(b.rate == 100.0);
  CHECK(b.count == 0);
  CHECK(b.mode == 0);
  CHECK(b.gains == std::vector<std::int32_t>{1, 2});
  CHECK(b.stream.id == "s0");
  CHECK(b.rate_changes.empty()); // defaults are no configure
  auto all = set.query({});
  REQUIRE(all.has_value());
  CHECK(all->at("label") == "none"); // unbound, from the PRF
  CHECK(all->at("stream") ==
        Json{{"stream_id", "s0"}, {"sample_rate", 0.0}, {"taps", Json::array()}});
  CHECK_FALSE(all->contains("secret"));   // write-only
  CHECK_FALSE(all->contains("capacity")); // allocation only
}

TEST_CASE("bindings that do not fit the PRF are refused, every one named", "[component]") {
  double wrong_type = 0;
  std::vector<double> wrong_form;
  Stream stream;
  PropertySet set;
  set.bind("mode", std::make_unique<detail::ScalarBinding<double>>(wrong_type, nullptr));
  set.bind("rate_hz", std::make_unique<detail::SequenceBinding<double>>(wrong_form, nullptr));
  set.bind("nope", std::make_unique<detail::ScalarBinding<double>>(wrong_type, nullptr));
  set.bind("stream", std::make_unique<detail::StructBinding<Stream>>(
                         stream, std::vector<Field<Stream>>{{"stream_id", &Stream::id}}, nullptr));
  auto loaded = set.load(definitions());
  REQUIRE_FALSE(loaded.has_value());
  const std::string text = loaded.error().to_string();
  CHECK_THAT(text, Catch::Contains("property \"mode\": the variable holds double, the PRF type "
                                   "short needs std::int16_t"));
  CHECK_THAT(text, Catch::Contains("property \"rate_hz\": the variable is a std::vector"));
  CHECK_THAT(text, Catch::Contains("property \"nope\" is bound, but the PRF does not define it"));
  CHECK_THAT(text, Catch::Contains("property \"stream\": member \"sample_rate\" has no field"));
}

TEST_CASE("configure applies all values or none, then runs the change callbacks", "[component]") {
  Bound b;
  auto set = b.properties();
  REQUIRE(set.load(definitions()).has_value());

  auto applied = set.configure({{"rate_hz", 250},
                                {"mode", "on"},
                                {"label", "x"},
                                {"stream", {{"sample_rate", 48000}}},
                                {"secret", "s"}});
  REQUIRE(applied.has_value());
  CHECK(b.rate == 250.0);
  CHECK(b.mode == 1);
  CHECK(b.stream.rate == 48000.0);
  CHECK(b.stream.id == "s0"); // a struct configure updates the members it names
  CHECK(b.secret == "s");
  CHECK(b.rate_changes.empty()); // callbacks run when the caller says
  REQUIRE(applied->size() == 1);
  applied->front()();
  CHECK(b.rate_changes == std::vector<std::pair<double, double>>{{100.0, 250.0}});
  CHECK(set.query({"label"})->at("label") == "x");

  const auto message = configure_error(set.configure(
      {{"rate_hz", 500}, {"count", 1}, {"capacity", 1}, {"unknown", 1}, {"mode", 3}}));
  CHECK_THAT(message, Catch::Contains("property \"count\" is read-only"));
  CHECK_THAT(message,
             Catch::Contains("property \"capacity\" is not configurable (kind allocation)"));
  CHECK_THAT(message, Catch::Contains("unknown property \"unknown\""));
  CHECK_THAT(message, Catch::Contains("property \"mode\": 3 is none of its enumerations"));
  CHECK(b.rate == 250.0); // the valid one was not applied either
  CHECK(configure_error(set.configure(Json::array())) ==
        "\"properties\" must be an object of property ids and values");

  auto secret = set.query({"secret"});
  REQUIRE_FALSE(secret.has_value());
  CHECK(secret.error().message == "property \"secret\" is write-only");
}

TEST_CASE("execparams are applied from their command-line text", "[component]") {
  Bound b;
  auto set = b.properties();
  REQUIRE(set.load(definitions()).has_value());
  CHECK(set.apply_text("rate_hz", "12.5").has_value());
  CHECK(b.rate == 12.5);
  CHECK(set.apply_text("mode", "on").has_value());
  CHECK(b.mode == 1);
  CHECK(set.apply_text("rate_hz", "5000").error() ==
        "property \"rate_hz\": 5000.0 is outside its range 0.1..1000");
  CHECK(set.apply_text("rate_hz", "fast").error() ==
        "property \"rate_hz\": \"fast\" is not a valid double");
  CHECK(set.apply_text("gains", "1").error() == "property \"gains\" is not a simple");
}

TEST_CASE("exec parameters come in pairs and name the component", "[component]") {
  const char *argv[] = {"rsca-producer",
                        "COMPONENT_IDENTIFIER",
                        "P_1:app",
                        "PROFILE_NAME",
                        "/sdr/P.spd.xml",
                        "CONTROL_ADDRESS",
                        "rsca/component/app/P_1",
                        "rate_hz",
                        "20"};
  auto params = parse_exec_params(9, argv);
  REQUIRE(params.has_value());
  CHECK(params->identifier == "P_1:app");
  CHECK(params->name_binding == "P_1:app"); // the identifier when NAME_BINDING is absent
  CHECK(params->profile == "/sdr/P.spd.xml");
  CHECK(params->control_address == "rsca/component/app/P_1");
  CHECK(params->others == std::vector<std::pair<std::string, std::string>>{{"rate_hz", "20"}});
  CHECK(parse_exec_params(8, argv).error() ==
        "exec parameters come in pairs: \"rate_hz\" has no value");
  CHECK(parse_exec_params(5, argv).error() == "the exec parameter CONTROL_ADDRESS is missing");
}

TEST_CASE("a component host's exec parameters are its address, then one group per component, "
          "each with its library",
          "[component]") {
  const char *argv[] = {"rsca-component-host",
                        "CONTROL_ADDRESS",
                        "host",
                        "COMPONENT_IDENTIFIER",
                        "A_1",
                        "PROFILE_NAME",
                        "/sdr/A.spd.xml",
                        "CONTROL_ADDRESS",
                        "a",
                        "LIBRARY",
                        "liba.so",
                        "rate_hz",
                        "20",
                        "COMPONENT_IDENTIFIER",
                        "B_1",
                        "PROFILE_NAME",
                        "/sdr/B.spd.xml",
                        "CONTROL_ADDRESS",
                        "b",
                        "LIBRARY",
                        "/lib/libb.so"};
  auto host = parse_host_params(21, argv);
  REQUIRE(host.has_value());
  CHECK(host->control_address == "host");
  const auto &hosted = host->components;
  REQUIRE(hosted.size() == 2);
  CHECK(hosted[0].identifier == "A_1");
  CHECK(hosted[0].control_address == "a");
  CHECK(hosted[0].library == "liba.so");
  // LIBRARY is the host's; the rest goes to the component.
  CHECK(hosted[0].others == std::vector<std::pair<std::string, std::string>>{{"rate_hz", "20"}});
  CHECK(hosted[1].control_address == "b");
  CHECK(hosted[1].library == "/lib/libb.so");
  CHECK(hosted[1].others.empty());
  // Bad input: a clear error naming what is wrong.
  CHECK(parse_host_params(19, argv).error() == "B_1: the exec parameter LIBRARY is missing");
  CHECK(parse_host_params(14, argv).error() ==
        "component 2: exec parameters come in pairs: \"COMPONENT_IDENTIFIER\" has no value");
  CHECK(parse_host_params(3, argv).error() ==
        "the host's address is followed by components, each starting with COMPONENT_IDENTIFIER");
  const char *no_address[] = {"rsca-component-host", "COMPONENT_IDENTIFIER", "A_1"};
  CHECK(parse_host_params(3, no_address).error() ==
        "the exec parameters start with CONTROL_ADDRESS <the host's address>");
}

TEST_CASE("the schedule admission decided arrives as exec parameters", "[component]") {
  const char *argv[] = {"rsca-producer",
                        "COMPONENT_IDENTIFIER",
                        "P_1",
                        "PROFILE_NAME",
                        "/sdr/P.spd.xml",
                        "CONTROL_ADDRESS",
                        "rsca/c/P_1",
                        "RSCA_CPU",
                        "1",
                        "RSCA_PRIORITY",
                        "7",
                        "RSCA_PERIOD_NS",
                        "20000000",
                        "RSCA_BUDGET_NS",
                        "1000000",
                        "RSCA_DEADLINE_NS",
                        "15000000",
                        "rate_hz",
                        "20"};
  auto params = parse_exec_params(19, argv);
  REQUIRE(params.has_value());
  REQUIRE(params->schedule.has_value());
  CHECK(params->schedule->cpu == 1);
  CHECK(params->schedule->priority == 7);
  CHECK(params->schedule->period == std::chrono::milliseconds(20));
  CHECK(params->schedule->budget == std::chrono::milliseconds(1));
  CHECK(params->schedule->deadline == std::chrono::milliseconds(15));
  // The schedule's parameters are not properties.
  CHECK(params->others == std::vector<std::pair<std::string, std::string>>{{"rate_hz", "20"}});

  const char *bad[] = {"c",    "COMPONENT_IDENTIFIER", "P_1", "PROFILE_NAME",
                       "/p",   "CONTROL_ADDRESS",      "a",   "RSCA_CPU",
                       "first"};
  CHECK(parse_exec_params(9, bad).error() ==
        "the exec parameter RSCA_CPU is not a number: \"first\"");
  const char *none[] = {"c",  "COMPONENT_IDENTIFIER", "P_1", "PROFILE_NAME",
                        "/p", "CONTROL_ADDRESS",      "a"};
  CHECK_FALSE(parse_exec_params(7, none)->schedule.has_value());
}

TEST_CASE("CF control interfaces are called, not carried as data", "[component]") {
  // A uses port of one of these is a ResourceUsesPort, connected to a supported interface.
  for (const char *repid :
       {"IDL:CF/Resource:1.0", "IDL:CF/PropertySet:1.0", "IDL:CF/LifeCycle:1.0"}) {
    INFO(repid);
    CHECK(rsca::profile::is_control_interface(repid));
    CHECK_FALSE(port::port_type_for_repid(repid).has_value());
  }
  for (const char *repid : {"IDL:rsca/SampleSeq:1.0", "IDL:CF/Device:1.0", "IDL:CF/Resource:2.0"})
    CHECK_FALSE(rsca::profile::is_control_interface(repid));
}

TEST_CASE("repids map to the port types of ports.idl", "[component]") {
  CHECK(port::port_type_for_repid("IDL:rsca/SampleSeq:1.0") == port::PortType::Samples);
  CHECK(port::port_type_for_repid("IDL:BULKIO/dataFloat:1.0") == port::PortType::Samples);
  CHECK(port::port_type_for_repid("IDL:BULKIO/dataShort:1.0") == port::PortType::Samples);
  CHECK(port::port_type_for_repid("IDL:ExtendedEvent/MessageEvent:1.0") ==
        port::PortType::PropertyEvent);
  CHECK(port::port_type_for_repid("IDL:rsca/PropertyEvent:1.0") == port::PortType::PropertyEvent);
  CHECK(port::port_type_for_repid("IDL:rsca/Command:1.0") == port::PortType::Command);
  CHECK_FALSE(port::port_type_for_repid("IDL:BULKIO/data:1.0").has_value());
  CHECK_FALSE(port::port_type_for_repid("IDL:CF/Resource:1.0").has_value());
}

TEST_CASE("a component declares its properties and ports in its constructor", "[component]") {
  Declarations component(Context{});
  CHECK(component.state() == State::Loaded);
  CHECK(to_string(component.state()) == "loaded");
}
