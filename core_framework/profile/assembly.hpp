// The parts SADs and DCDs share: component files, placements and instantiations, and
// connections with RSCA's QoS and timing extensions.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/diagnostic.hpp"
#include "common/units.hpp"
#include "profile/property_refs.hpp"
#include "profile/spd.hpp"

namespace rsca::profile {

struct ComponentFile {
  std::string id;
  std::string type; // "SPD"
  LocalFile file;
  SourceLocation where;
};

enum class Criticality : std::uint8_t { Low, Medium, High, Safety };
std::string_view to_string(Criticality criticality);

// RSCA extension: timing of one component instance.
struct Timing {
  std::optional<Duration> period;
  std::optional<Duration> deadline;
  std::optional<Duration> execution_time;
  std::optional<std::uint32_t> priority;
  std::optional<Criticality> criticality;
  SourceLocation where;
};

// REDHAWK's affinity directive (affinity::exec_directive_class and _value): where the node lets
// the process run. rsca adds "nice".
struct ProcessorAffinity {
  enum class Class : std::uint8_t {
    Cpu,    // value: CPUs, as a list such as "0-3,6"
    Socket, // value: NUMA nodes, as a list; the process runs on their CPUs
    Nic,    // value: a network interface; the process runs on the CPUs that serve it
    Nice,   // value: a nice value, -20 to 19
  };
  Class directive = Class::Cpu;
  std::string value;
  SourceLocation where;
};
std::string_view to_string(ProcessorAffinity::Class directive);

// REDHAWK's loggingconfig: the initial log level of a component or device, and a logging
// configuration URI (a log4cxx file for REDHAWK's runtimes; rsca's runtime logs with spdlog and
// passes it on as LOGGING_CONFIG_URI without reading it).
struct LoggingConfig {
  std::optional<int> debug_level; // REDHAWK's DEBUG_LEVEL: 0 fatal ... 5 trace
  std::string uri;
  SourceLocation where;
};

struct ComponentInstantiation {
  std::string id;
  std::string usage_name;
  std::optional<std::uint32_t> start_order;
  std::vector<PropertyRef> properties;      // componentproperties: overrides of PRF values
  std::vector<PropertyRef> device_requires; // SAD devicerequires / DCD deployerrequires
  std::string naming_service_name;          // findcomponent/namingservice, kept for REDHAWK
  std::optional<Timing> timing;
  std::optional<ProcessorAffinity> affinity;
  std::optional<LoggingConfig> logging;
  SourceLocation where;
};

struct ComponentPlacement {
  std::string componentfile_ref;
  SourceLocation ref_where;
  std::vector<ComponentInstantiation> instantiations;
  // DCD only.
  std::string deploy_on_device;
  std::string composite_part_of_device;
  std::optional<LocalFile> device_pkg_file; // DPD
  // SAD only: the hostcollocation this placement belongs to, if any.
  std::string host_collocation;
};

struct HostCollocation {
  std::string id;
  std::string name;
  // What its placements name it by (ComponentPlacement::host_collocation), unique in its SAD: its
  // id, or for one without (REDHAWK allows it) its name and its place among the collocations.
  std::string key;
  SourceLocation where;
  // REDHAWK 2.2: usesdevice ids of the SAD whose devices the collocation goes next to.
  std::vector<std::string> uses_device_refs;
  std::vector<SourceLocation> uses_device_ref_where;
  // REDHAWK 2.2's reservation of kind cpucores: the collocation as a whole is charged at least
  // that many cores on its host.
  std::optional<double> cpu_cores;
};

// How a connection end finds its object.
struct FindBy {
  enum class Kind : std::uint8_t { NamingService, DomainFinder, StringifiedObjectRef };
  Kind kind = Kind::NamingService;
  std::string type; // domainfinder type: "eventchannel", "filemanager", ...
  std::string name;
  bool is_event_channel() const { return kind == Kind::DomainFinder && type == "eventchannel"; }
};

struct EndpointTarget {
  enum class Kind : std::uint8_t {
    ComponentInstantiation,
    DeviceThatLoadedThisComponent,
    DeviceUsedByThisComponent,
    DeviceUsedByApplication, // SAD only: the device of one of the SAD's own usesdevice
    FindBy,
  };
  Kind kind = Kind::ComponentInstantiation;
  std::string refid;     // the component instantiation (for device refs: the component)
  std::string usesrefid; // DeviceUsedBy*: the usesdevice id
  FindBy findby;
  SourceLocation where; // the reference element itself
};

struct UsesEnd {
  std::string port;
  EndpointTarget target;
  SourceLocation where;
};

struct ProvidesEnd {
  enum class Kind : std::uint8_t { Port, SupportedInterface, FindBy };
  Kind kind = Kind::Port;
  std::string port; // provides port name, or the supported interface's repid
  EndpointTarget target;
  SourceLocation where;
};

enum class Reliability : std::uint8_t { BestEffort, Reliable };
enum class Durability : std::uint8_t { Volatile, TransientLocal, Transient, Persistent };
enum class History : std::uint8_t { KeepLast, KeepAll };
enum class Liveliness : std::uint8_t { Automatic, ManualByParticipant, ManualByTopic };
enum class Ownership : std::uint8_t { Shared, Exclusive };
// How a connection between processes travels: through their nodes (shared memory on one host),
// or on DDS from the components' own participants (a high-rate stream between hosts).
enum class Transport : std::uint8_t { Node, Direct, Tcp };

std::string_view to_string(Reliability v);
std::string_view to_string(Durability v);
std::string_view to_string(History v);
std::string_view to_string(Liveliness v);
std::string_view to_string(Ownership v);
std::string_view to_string(Transport v);

// RSCA extension: the QoS one connection asks for. Absent fields take the defaults documented in
// docs/profiles.md.
struct ConnectionQos {
  std::optional<Reliability> reliability;
  std::optional<Durability> durability;
  std::optional<History> history;
  std::optional<std::uint32_t> depth;
  std::optional<Duration> deadline;
  std::optional<Duration> latency_budget;
  std::optional<std::int32_t> transport_priority;
  std::optional<Liveliness> liveliness;
  std::optional<Duration> lease;
  std::optional<Ownership> ownership;
  std::optional<std::int32_t> strength;
  std::optional<Transport> transport;
  SourceLocation where;
};

struct Connection {
  std::string id; // may be empty in plain SCA
  UsesEnd uses;
  ProvidesEnd provides;
  std::optional<ConnectionQos> qos;
  std::optional<std::string> filter; // content filter of an event-channel subscriber
  SourceLocation where;

  bool publishes_to_channel() const {
    return provides.kind == ProvidesEnd::Kind::FindBy && provides.target.findby.is_event_channel();
  }
  bool subscribes_to_channel() const {
    return uses.target.kind == EndpointTarget::Kind::FindBy &&
           uses.target.findby.is_event_channel();
  }
};

} // namespace rsca::profile
