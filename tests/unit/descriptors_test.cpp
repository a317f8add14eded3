// Each descriptor type read from the project's own SDR root (profiles/), with the values its
// files hold.
#include "profile/descriptor.hpp"
#include "profile/profile_loader.hpp"
#include "profile/property_binding.hpp"

#include <catch2/catch.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <variant>
#include <vector>

using namespace rsca;
using namespace rsca::profile;
using namespace std::chrono_literals;
using Catch::Matchers::Contains;

namespace fs = std::filesystem;

namespace {

const fs::path kProfiles = fs::path(RSCA_SOURCE_DIR) / "profiles";
const fs::path kSad = kProfiles / "dom/waveforms/ProducerConsumer/ProducerConsumer.sad.xml";
const fs::path kProducer = kProfiles / "dom/components/Producer";
const fs::path kConsumer = kProfiles / "dom/components/Consumer";
const fs::path kGpp = kProfiles / "dev/devices/GPP";
const fs::path kNode1 = kProfiles / "dev/nodes/node1/DeviceManager.dcd.xml";
const fs::path kNode2 = kProfiles / "dev/nodes/node2/DeviceManager.dcd.xml";
const fs::path kDmd = kProfiles / "dom/domain/DomainManager.dmd.xml";

// The descriptor of type T in `file`, failing the test when it does not read or is another type.
template <typename T>
T read(const fs::path &file) {
  INFO(file.string());
  auto descriptor = read_descriptor(file);
  if (!descriptor)
    FAIL("read failed:\n" << descriptor.error().to_string());
  T *typed = std::get_if<T>(&*descriptor);
  REQUIRE(typed != nullptr);
  return std::move(*typed);
}

// The definition of `id` in `prf`, of form D.
template <typename D>
const D &definition(const Properties &prf, std::string_view id) {
  INFO("property " << id);
  const PropertyDefinition *d = prf.find(id);
  REQUIRE(d != nullptr);
  const D *typed = std::get_if<D>(d);
  REQUIRE(typed != nullptr);
  return *typed;
}

// The value of alternative T held by a scalar.
template <typename T>
T as(const Scalar &scalar) {
  const T *value = std::get_if<T>(&scalar);
  REQUIRE(value != nullptr);
  return *value;
}

template <typename T>
T as(const std::optional<Scalar> &scalar) {
  REQUIRE(scalar.has_value());
  return as<T>(*scalar);
}

// The scalar a struct value holds for `member`.
const Scalar &member_of(const StructValue &value, std::string_view member) {
  for (const auto &[id, v] : value.members)
    if (id == member) {
      const Scalar *scalar = std::get_if<Scalar>(&v);
      REQUIRE(scalar != nullptr);
      return *scalar;
    }
  FAIL("no member " << member);
  throw;
}

const ComponentInstantiation &instantiation(const SoftwareAssembly &sad, std::string_view id) {
  const ComponentInstantiation *ci = sad.find_instantiation(id);
  REQUIRE(ci != nullptr);
  return *ci;
}

// A copy of the project's components in an SDR root of its own, removed afterwards.
class ScratchSdrRoot {
public:
  ScratchSdrRoot() {
    std::random_device random;
    root_ = fs::temp_directory_path() / ("rsca_descriptors_test_" + std::to_string(random()));
    fs::create_directories(root_ / "dom/waveforms");
    fs::copy(kProfiles / "dom/components", root_ / "dom/components", fs::copy_options::recursive);
  }
  ~ScratchSdrRoot() {
    std::error_code ec;
    fs::remove_all(root_, ec);
  }
  ScratchSdrRoot(const ScratchSdrRoot &) = delete;
  ScratchSdrRoot &operator=(const ScratchSdrRoot &) = delete;

  // Writes the ProducerConsumer SAD with `from` replaced by `to` under dom/waveforms.
  fs::path sad_with(std::string_view from, std::string_view to) const {
    std::ifstream in(kSad);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto at = text.find(from);
    REQUIRE(at != std::string::npos);
    text.replace(at, from.size(), to);
    const fs::path file = root_ / "dom/waveforms/Edited.sad.xml";
    std::ofstream(file) << text;
    return file;
  }

private:
  fs::path root_;
};

} // namespace

TEST_CASE("SAD: the ProducerConsumer application", "[descriptors][sad]") {
  const auto sad = read<SoftwareAssembly>(kSad);
  CHECK(sad.name == "ProducerConsumer");
  CHECK(sad.id == "DCE:ab8bc938-a4e4-4e4c-9bf5-70a1e903337f");
  CHECK(sad.version == "0.1.0");
  CHECK_THAT(sad.description, Contains("Producer_1 publishes sample sequences"));

  REQUIRE(sad.component_files.size() == 2);
  CHECK(sad.component_files[0].id == "Producer_spd");
  CHECK(sad.component_files[0].type == "SPD");
  CHECK(sad.component_files[0].file.name == "/components/Producer/Producer.spd.xml");
  CHECK(sad.component_files[0].file.where.line == 7);
  CHECK(sad.component_files[1].id == "Consumer_spd");
  CHECK(sad.component_files[1].file.name == "/components/Consumer/Consumer.spd.xml");
  CHECK(sad.find_component_file("Consumer_spd") == &sad.component_files[1]);
  CHECK(sad.find_component_file("Nothing_spd") == nullptr);

  REQUIRE(sad.placements.size() == 2);
  CHECK(sad.placements[0].componentfile_ref == "Producer_spd");
  CHECK(sad.placements[1].componentfile_ref == "Consumer_spd");
  CHECK(sad.host_collocations.empty());
  const ComponentPlacement *placement = nullptr;
  const ComponentInstantiation *producer = sad.find_instantiation("Producer_1", &placement);
  REQUIRE(producer != nullptr);
  CHECK(placement == &sad.placements[0]);
  CHECK(producer->usage_name == "Producer_1");
  CHECK(producer->start_order == 1u);
  CHECK(producer->naming_service_name == "Producer_1");
  CHECK(producer->where.line == 16);
  const ComponentInstantiation &consumer = instantiation(sad, "Consumer_1");
  CHECK(consumer.start_order == 0u);
  CHECK(consumer.properties.empty());
  CHECK_FALSE(consumer.timing.has_value());

  REQUIRE(producer->timing.has_value());
  CHECK(producer->timing->period == Duration{20ms});
  CHECK(producer->timing->priority == 10u);
  CHECK_FALSE(producer->timing->deadline.has_value());
  CHECK_FALSE(producer->timing->execution_time.has_value());
  CHECK_FALSE(producer->timing->criticality.has_value());
  CHECK(producer->timing->where.line == 24);

  CHECK(sad.assembly_controller == "Consumer_1");
  CHECK(sad.assembly_controller_where.line == 38);

  REQUIRE(sad.connections.size() == 1);
  const Connection &c = sad.connections.front();
  CHECK(c.id == "samples");
  CHECK(c.where.line == 41);
  CHECK(c.uses.port == "samples_out");
  CHECK(c.uses.target.kind == EndpointTarget::Kind::ComponentInstantiation);
  CHECK(c.uses.target.refid == "Producer_1");
  CHECK(c.provides.kind == ProvidesEnd::Kind::Port);
  CHECK(c.provides.port == "samples_in");
  CHECK(c.provides.target.refid == "Consumer_1");
  CHECK_FALSE(c.filter.has_value());
  REQUIRE(c.qos.has_value());
  CHECK(c.qos->reliability == Reliability::Reliable);
  CHECK(c.qos->history == History::KeepLast);
  CHECK(c.qos->depth == 16u);
  CHECK(c.qos->deadline == Duration{100ms});
  CHECK_FALSE(c.qos->durability.has_value());
  CHECK_FALSE(c.qos->ownership.has_value());
  CHECK(c.qos->where.line == 50);

  REQUIRE(sad.external_ports.size() == 1);
  CHECK(sad.external_ports[0].external_name == "samples_tap");
  CHECK(sad.external_ports[0].port == "samples_out");
  CHECK(sad.external_ports[0].kind == ExternalPort::Kind::Uses);
  CHECK(sad.external_ports[0].component_ref == "Producer_1");
  REQUIRE(sad.external_properties.size() == 1);
  CHECK(sad.external_properties[0].component_ref == "Producer_1");
  CHECK(sad.external_properties[0].property_id == "rate_hz");
  CHECK(sad.external_properties[0].external_id == "producer_rate_hz");
  CHECK(sad.external_properties[0].where.line == 61);
  CHECK(sad.latency_paths.empty());
  CHECK(sad.uses_device_dependencies.empty());
}

TEST_CASE("SAD: the rate_hz override binds to a typed double", "[descriptors][sad][binding]") {
  const auto sad = read<SoftwareAssembly>(kSad);
  const auto prf = read<Properties>(kProducer / "Producer.prf.xml");
  const ComponentInstantiation &producer = instantiation(sad, "Producer_1");
  REQUIRE(producer.properties.size() == 1);
  const auto *ref = std::get_if<SimpleRef>(&producer.properties.front());
  REQUIRE(ref != nullptr);
  CHECK(ref->refid == "rate_hz");
  CHECK(ref->value == "50.0");
  CHECK(ref->where.line == 19);

  const PropertyDefinition *rate = prf.find("rate_hz");
  REQUIRE(rate != nullptr);
  const auto bound = bind_property(*rate, producer.properties.front());
  if (!bound)
    FAIL(bound.error().to_string());
  const Scalar *scalar = std::get_if<Scalar>(&*bound);
  REQUIRE(scalar != nullptr);
  CHECK(as<double>(*scalar) == 50.0);

  // The same ref with a value outside rate_hz's range (0.1..10000) does not bind.
  SimpleRef too_fast = *ref;
  too_fast.value = "20000";
  const auto refused = bind_property(*rate, PropertyRef(too_fast));
  REQUIRE_FALSE(refused.has_value());
  const Diagnostic &d = refused.error().diagnostics().front();
  CHECK(d.rule == "range");
  CHECK(d.where.line == 19);
  CHECK_THAT(d.message, Contains("outside its range"));
}

TEST_CASE("SPD: Producer and Consumer packages", "[descriptors][spd]") {
  const auto producer = read<SoftPkg>(kProducer / "Producer.spd.xml");
  CHECK(producer.name == "Producer");
  CHECK(producer.id == "DCE:97523df1-a3b2-4a9d-bef1-4dc2422395d8");
  CHECK(producer.version == "0.1.0");
  CHECK(producer.title == "Producer");
  CHECK(producer.authors == std::vector<std::string>{"rsca"});
  REQUIRE(producer.property_file.has_value());
  CHECK(producer.property_file->name == "Producer.prf.xml");
  REQUIRE(producer.descriptor.has_value());
  CHECK(producer.descriptor->name == "Producer.scd.xml");
  CHECK(producer.uses_devices.empty());

  REQUIRE(producer.implementations.size() == 1);
  const Implementation &cpp = producer.implementations.front();
  CHECK(producer.find_implementation("cpp") == &cpp);
  CHECK(producer.find_implementation("python") == nullptr);
  CHECK(cpp.description == "C++ implementation.");
  CHECK(cpp.code.type == CodeType::Executable);
  CHECK(to_string(cpp.code.type) == "Executable");
  CHECK(cpp.code.file.name == "rsca-producer");
  CHECK(cpp.code.entrypoint == "rsca-producer");
  CHECK(cpp.programming_language == "C++");
  CHECK(cpp.human_language == "EN");
  REQUIRE(cpp.os.size() == 1);
  CHECK(cpp.os[0].name == "Linux");
  CHECK(cpp.os[0].version.empty());
  CHECK(cpp.processors == std::vector<std::string>{"x86_64"});
  CHECK(cpp.softpkg_dependencies.empty());
  CHECK(cpp.property_dependencies.empty());
  CHECK_FALSE(cpp.property_file.has_value());

  REQUIRE(cpp.resource_demand.has_value());
  CHECK(cpp.resource_demand->utilization.value() == Approx(0.05));
  CHECK(cpp.resource_demand->memory_bytes == 33'554'432u);
  CHECK_FALSE(cpp.resource_demand->execution_time.has_value());
  CHECK_FALSE(cpp.resource_demand->period.has_value());
  CHECK_FALSE(cpp.resource_demand->bandwidth_bps.has_value());
  CHECK(cpp.resource_demand->where.line == 25);

  const auto consumer = read<SoftPkg>(kConsumer / "Consumer.spd.xml");
  CHECK(consumer.name == "Consumer");
  REQUIRE(consumer.implementations.size() == 1);
  CHECK(consumer.implementations[0].code.file.name == "rsca-consumer");
  CHECK(consumer.implementations[0].resource_demand->memory_bytes == 33'554'432u);

  // The GPP device package declares no demand of its own.
  const auto gpp = read<SoftPkg>(kGpp / "GPP.spd.xml");
  CHECK(gpp.implementations.at(0).code.type == CodeType::SharedLibrary);
  CHECK(gpp.implementations.at(0).code.file.name == "librsca-gpp.so");
  CHECK_FALSE(gpp.implementations.at(0).resource_demand.has_value());
}

TEST_CASE("SPD: code stacksize and priority", "[descriptors][spd]") {
  const auto doc = read_xml_profile_text(R"(<softpkg id="DCE:1" name="Sized">
  <author><name>rsca</name></author>
  <implementation id="cpp">
    <code type="Executable">
      <localfile name="bin/sized"/>
      <entrypoint>bin/sized</entrypoint>
      <stacksize>65536</stacksize>
      <priority>5</priority>
    </code>
  </implementation>
</softpkg>)",
                                         "sized.spd.xml");
  if (!doc)
    FAIL(doc.error().to_string());
  const auto spd = read_spd(*doc);
  REQUIRE(spd.has_value());
  const Code &code = spd->implementations.at(0).code;
  CHECK(code.stack_size.value_or(0) == 65536u);
  CHECK(code.priority.value_or(0) == 5u);
}

TEST_CASE("SCD: ports, repids and directions", "[descriptors][scd]") {
  const auto producer = read<SoftwareComponent>(kProducer / "Producer.scd.xml");
  CHECK(producer.corba_version == "2.2");
  CHECK(producer.component_repid == "IDL:CF/Resource:1.0");
  CHECK(producer.component_type == "resource");
  CHECK(producer.supported_interfaces.size() == 5);
  REQUIRE(producer.ports.size() == 2);
  const PortDefinition &out = producer.ports.front();
  CHECK(out.name == "samples_out");
  CHECK(out.repid == "IDL:rsca/SampleSeq:1.0");
  CHECK(out.direction == PortDirection::Uses);
  CHECK(out.port_types == std::vector<std::string>{"data"});
  CHECK_THAT(out.description, Contains("payload_size bytes each"));
  CHECK(out.where.line == 14);
  CHECK(producer.find_port("samples_out", PortDirection::Uses) == &out);
  CHECK(producer.find_port("samples_out", PortDirection::Provides) == nullptr);
  const PortDefinition &events = producer.ports.back();
  CHECK(events.name == "events_out");
  CHECK(events.repid == "IDL:rsca/PropertyEvent:1.0");
  CHECK(events.direction == PortDirection::Uses);
  CHECK(producer.interfaces.size() == 7);
  CHECK(producer.supports("IDL:CF/LifeCycle:1.0"));
  CHECK_FALSE(producer.supports("IDL:CF/Device:1.0"));

  const auto consumer = read<SoftwareComponent>(kConsumer / "Consumer.scd.xml");
  REQUIRE(consumer.ports.size() == 2);
  CHECK(consumer.ports[0].name == "samples_in");
  CHECK(consumer.ports[1].name == "events_in");
  CHECK(consumer.ports[1].direction == PortDirection::Provides);
  CHECK(consumer.ports[0].repid == "IDL:rsca/SampleSeq:1.0");
  CHECK(consumer.ports[0].direction == PortDirection::Provides);
  CHECK(consumer.find_port("samples_in", PortDirection::Provides) != nullptr);
  CHECK(consumer.find_port("samples_in", PortDirection::Uses) == nullptr);

  const auto gpp = read<SoftwareComponent>(kGpp / "GPP.scd.xml");
  CHECK(gpp.component_type == "executabledevice");
  CHECK(gpp.component_repid == "IDL:CF/ExecutableDevice:1.0");
  CHECK(gpp.ports.empty());
  CHECK(gpp.supports("IDL:CF/LoadableDevice:1.0"));
  REQUIRE(gpp.interfaces.size() == 8);
  CHECK(gpp.interfaces[0].name == "ExecutableDevice");
  CHECK(gpp.interfaces[0].inherits == std::vector<std::string>{"IDL:CF/LoadableDevice:1.0"});
}

TEST_CASE("SAD: an external port naming a supported interface", "[descriptors][sad]") {
  ScratchSdrRoot root;
  const fs::path sad =
      root.sad_with("<usesidentifier>samples_out</usesidentifier>\n      "
                    "<componentinstantiationref refid=\"Producer_1\"/>\n    </port>",
                    "<supportedidentifier>IDL:CF/Resource:1.0</supportedidentifier>\n"
                    "      <componentinstantiationref refid=\"Producer_1\"/>\n    </port>");
  ProfileLoader loader;
  const auto app = loader.load_application(sad);
  if (!app)
    FAIL(app.error().to_string());
  for (const auto &w : app->warnings)
    UNSCOPED_INFO(to_string(w));
  CHECK(app->warnings.empty());
}

TEST_CASE("PRF: Producer's simples and struct", "[descriptors][prf]") {
  const auto prf = read<Properties>(kProducer / "Producer.prf.xml");
  REQUIRE(prf.properties.size() == 5);

  const auto &rate = definition<SimpleProperty>(prf, "rate_hz");
  CHECK(rate.name == "rate_hz");
  CHECK(rate.type == TypeSpec{SimpleType::Double, false});
  CHECK(as<double>(rate.value) == 100.0);
  CHECK(rate.units == "Hz");
  REQUIRE(rate.range.has_value());
  CHECK(as<double>(rate.range->min) == 0.1);
  CHECK(as<double>(rate.range->max) == 10000.0);
  CHECK(rate.kinds == std::vector<PropertyKind>{PropertyKind::Property});
  CHECK(rate.has_kind(PropertyKind::Property));
  CHECK_FALSE(rate.has_kind(PropertyKind::Configure));
  CHECK(rate.action == Action::External);
  CHECK(rate.mode == AccessMode::ReadWrite);
  CHECK(rate.description == "Publication rate.");
  CHECK(rate.where.line == 4);

  const auto &payload = definition<SimpleProperty>(prf, "payload_size");
  CHECK(payload.type.type == SimpleType::ULong);
  CHECK(as<std::uint32_t>(payload.value) == 64u);
  CHECK(payload.units == "samples");
  CHECK_FALSE(payload.range.has_value());

  const auto &message = definition<SimpleProperty>(prf, "message");
  CHECK(message.type.type == SimpleType::String);
  CHECK(as<std::string>(message.value) == "hello");
  CHECK(message.units.empty());

  const auto &last = definition<SimpleProperty>(prf, "last_sequence");
  CHECK(last.type.type == SimpleType::ULongLong);
  CHECK(last.mode == AccessMode::ReadOnly);

  const auto &stream = definition<StructProperty>(prf, "stream");
  CHECK(stream.kinds == std::vector<PropertyKind>{PropertyKind::Property});
  CHECK(stream.mode == AccessMode::ReadWrite);
  REQUIRE(stream.members.size() == 2);
  const auto *stream_id = std::get_if<SimpleProperty>(stream.find_member("stream_id"));
  REQUIRE(stream_id != nullptr);
  CHECK(stream_id->type.type == SimpleType::String);
  CHECK(as<std::string>(stream_id->value) == "producer");
  const auto *sample_rate = std::get_if<SimpleProperty>(stream.find_member("sample_rate"));
  REQUIRE(sample_rate != nullptr);
  CHECK(sample_rate->type.type == SimpleType::Double);
  CHECK(sample_rate->units == "Hz");
  CHECK(stream.find_member("rate_hz") == nullptr);

  REQUIRE(stream.value.has_value());
  REQUIRE(stream.value->members.size() == 2);
  CHECK(stream.value->members[0].first == "stream_id");
  CHECK(as<std::string>(member_of(*stream.value, "stream_id")) == "producer");
  CHECK(as<double>(member_of(*stream.value, "sample_rate")) == 1000.0);
  const auto defaults = default_value(*prf.find("stream"));
  REQUIRE(defaults.has_value());
  CHECK(std::holds_alternative<StructValue>(*defaults));
}

TEST_CASE("PRF: Consumer counters and GPP allocation properties", "[descriptors][prf]") {
  const auto consumer = read<Properties>(kConsumer / "Consumer.prf.xml");
  const auto &received = definition<SimpleProperty>(consumer, "received");
  CHECK(received.type.type == SimpleType::ULongLong);
  CHECK(as<std::uint64_t>(received.value) == 0u);
  CHECK(received.mode == AccessMode::ReadOnly);
  const auto &latency = definition<SimpleProperty>(consumer, "last_latency_us");
  CHECK(latency.units == "us");
  CHECK(as<double>(latency.value) == 0.0);
  CHECK(definition<SimpleProperty>(consumer, "log_every").type.type == SimpleType::ULong);

  const auto gpp = read<Properties>(kGpp / "GPP.prf.xml");
  REQUIRE(gpp.properties.size() == 11);
  const auto &run_as = definition<SimpleProperty>(gpp, "run_as");
  CHECK(run_as.type.type == SimpleType::String);
  const auto &pin = definition<SimpleProperty>(gpp, "pin_admitted_cpu");
  CHECK(pin.type.type == SimpleType::Boolean);
  CHECK(as<bool>(pin.value));
  const auto &forks = definition<SimpleProperty>(gpp, "fork_server");
  CHECK(forks.type.type == SimpleType::Boolean);
  CHECK(as<bool>(forks.value));
  const auto &os = definition<SimpleProperty>(gpp, "DCE:4a23ad60-0b25-4121-a630-68803a498f75");
  CHECK(os.name == "os_name");
  CHECK(os.label() == "os_name");
  CHECK(as<std::string>(os.value) == "Linux");
  CHECK(os.has_kind(PropertyKind::Allocation));
  CHECK(os.action == Action::Eq);
  const auto &cpu = definition<SimpleProperty>(gpp, "cpu_capacity");
  CHECK(cpu.type.type == SimpleType::Double);
  CHECK_FALSE(cpu.value.has_value());
  CHECK(cpu.units == "%");
  CHECK(cpu.action == Action::External);
  CHECK_FALSE(default_value(*gpp.find("cpu_capacity")).has_value());
  CHECK(definition<SimpleProperty>(gpp, "mem_capacity").type.type == SimpleType::LongLong);
  CHECK(definition<SimpleProperty>(gpp, "mem_capacity").units == "MiB");
  CHECK(definition<SimpleProperty>(gpp, "nic_bandwidth").units == "Mbps");
  const auto &cores = definition<SimpleProperty>(gpp, "nbCores");
  CHECK(cores.type.type == SimpleType::UShort);
  CHECK(cores.kinds == std::vector<PropertyKind>{PropertyKind::Property});
  CHECK_FALSE(cores.action.has_value());
  const auto &policy = definition<SimpleProperty>(gpp, "scheduling_policy");
  CHECK(as<std::string>(policy.value) == "fixed-priority");
  CHECK(policy.enumerations.size() == 2);
}

TEST_CASE("DCD: node1 and node2", "[descriptors][dcd]") {
  const auto node1 = read<DeviceConfiguration>(kNode1);
  CHECK(node1.name == "node1");
  CHECK(node1.id == "DCE:f84aba57-3d9f-41c9-97e2-603b07e7eb5c");
  CHECK(node1.description == "Node node1: one GPP for the host.");
  CHECK(node1.device_manager_softpkg.name == "/mgr/DeviceManager.spd.xml");
  CHECK(node1.domain_manager == "rsca/rsca");
  REQUIRE(node1.component_files.size() == 1);
  CHECK(node1.component_files[0].id == "GPP_spd");
  CHECK(node1.component_files[0].file.name == "/devices/GPP/GPP.spd.xml");
  CHECK(node1.find_component_file("GPP_spd") == &node1.component_files[0]);
  REQUIRE(node1.placements.size() == 1);
  const ComponentPlacement &gpp = node1.placements[0];
  CHECK(gpp.componentfile_ref == "GPP_spd");
  REQUIRE(gpp.device_pkg_file.has_value());
  CHECK(gpp.device_pkg_file->name == "/devices/GPP/GPP.dpd.xml");
  CHECK(gpp.device_pkg_file->where.line == 17);
  REQUIRE(gpp.instantiations.size() == 1);
  CHECK(gpp.instantiations[0].id == "node1:GPP_1");
  CHECK(gpp.instantiations[0].usage_name == "GPP_1");
  CHECK_FALSE(gpp.instantiations[0].start_order.has_value());
  CHECK(gpp.deploy_on_device.empty());
  CHECK(node1.connections.empty());

  const auto node2 = read<DeviceConfiguration>(kNode2);
  CHECK(node2.name == "node2");
  REQUIRE(node2.placements.size() == 1);
  CHECK(node2.placements[0].instantiations.at(0).id == "node2:GPP_1");
  CHECK_FALSE(node2.placements[0].device_pkg_file.has_value());
}

TEST_CASE("DMD: the rsca domain", "[descriptors][dmd]") {
  const auto dmd = read<DomainManagerConfiguration>(kDmd);
  CHECK(dmd.name == "rsca");
  CHECK(dmd.id == "DCE:a54c5c53-27cc-4781-a15b-d23e0eaa71ad");
  CHECK(dmd.description == "The rsca domain.");
  CHECK(dmd.domain_manager_softpkg.name == "/mgr/DomainManager.spd.xml");
  CHECK(dmd.domain_manager_softpkg.where.line == 6);
}

TEST_CASE("DPD: the GPP's host processor", "[descriptors][dpd]") {
  const auto dpd = read<DevicePkg>(kGpp / "GPP.dpd.xml");
  CHECK(dpd.name == "GPP");
  CHECK(dpd.id == "DCE:e8a30080-5fb6-4af8-b633-c73bab267d4c");
  CHECK(dpd.version == "0.1.0");
  CHECK(dpd.title == "Host processor");
  CHECK(dpd.authors == std::vector<std::string>{"rsca"});
  const HardwareDevice &hw = dpd.hardware;
  CHECK(hw.id == "DCE:583f0852-6720-4e38-a7c7-21e3babf2561");
  CHECK(hw.name == "host_processor");
  CHECK(hw.version == "0.1.0");
  CHECK(hw.description == "Generic x86_64 processor.");
  CHECK(hw.manufacturer == "generic");
  CHECK(hw.model_number == "x86_64");
  CHECK(hw.device_classes == std::vector<std::string>{"Processor"});
  CHECK(hw.children.empty());
  CHECK_FALSE(hw.property_file.has_value());
}

TEST_CASE("descriptor types follow the root element", "[descriptors]") {
  const std::pair<fs::path, DescriptorType> files[] = {
      {kSad, DescriptorType::SAD},
      {kProducer / "Producer.spd.xml", DescriptorType::SPD},
      {kProducer / "Producer.scd.xml", DescriptorType::SCD},
      {kProducer / "Producer.prf.xml", DescriptorType::PRF},
      {kNode1, DescriptorType::DCD},
      {kDmd, DescriptorType::DMD},
      {kGpp / "GPP.dpd.xml", DescriptorType::DPD}};
  for (const auto &[file, type] : files) {
    INFO(file.string());
    const auto descriptor = read_descriptor(file);
    REQUIRE(descriptor.has_value());
    CHECK(type_of(*descriptor) == type);
  }
  CHECK(descriptor_type_of_root("softwareassembly") == DescriptorType::SAD);
  CHECK(descriptor_type_of_root("devicepkg") == DescriptorType::DPD);
  CHECK_FALSE(descriptor_type_of_root("softwareassemblies").has_value());
  CHECK(to_string(DescriptorType::DMD) == "DMD");
}

TEST_CASE("the loader resolves the project's own profiles cleanly", "[descriptors][loader]") {
  ProfileLoader loader;
  const auto app = loader.load_application(kSad);
  if (!app)
    FAIL(app.error().to_string());
  CHECK(app->warnings.empty());
  REQUIRE(app->component_files.size() == 2);
  const ResolvedSoftPkg *producer = app->softpkg_of(app->sad->placements[0]);
  REQUIRE(producer != nullptr);
  CHECK(producer->spd->name == "Producer");
  CHECK(producer->spd_path == (kProducer / "Producer.spd.xml").lexically_normal());
  REQUIRE(producer->scd != nullptr);
  CHECK(producer->scd->ports.at(0).name == "samples_out");
  REQUIRE(producer->find_property("payload_size") != nullptr);
  CHECK(producer->find_property("received") == nullptr);

  const auto node1 = loader.load_node(kNode1);
  if (!node1)
    FAIL(node1.error().to_string());
  CHECK(node1->warnings.empty());
  REQUIRE(node1->devices.size() == 1);
  REQUIRE(node1->devices[0].softpkg != nullptr);
  CHECK(node1->devices[0].softpkg->spd->name == "GPP");
  REQUIRE(node1->devices[0].device_pkg != nullptr);
  CHECK(node1->devices[0].device_pkg->hardware.manufacturer == "generic");
  const auto node2 = loader.load_node(kNode2);
  REQUIRE(node2.has_value());
  CHECK(node2->devices.at(0).device_pkg == nullptr);

  const auto domain = loader.load_domain(kDmd);
  REQUIRE(domain.has_value());
  CHECK(domain->name == "rsca");

  std::vector<std::string> problems;
  int checked = 0;
  for (const auto &entry : fs::recursive_directory_iterator(kProfiles)) {
    if (!entry.is_regular_file() || entry.path().extension() != ".xml")
      continue;
    ++checked;
    const auto validated = loader.validate(entry.path());
    if (!validated)
      problems.push_back(validated.error().to_string());
    else if (!validated->warnings.empty())
      problems.push_back(entry.path().string() + ": " + validated->warnings.front().message);
  }
  CHECK(checked > 20); // the walk found the profiles (22 when this was written)
  INFO(Catch::Detail::stringify(problems));
  CHECK(problems.empty());
}
