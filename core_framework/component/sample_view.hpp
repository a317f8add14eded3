// A viewer's reading of a port's DDS samples as JSON (rsca echo, rsca hz): the port types of
// component/port_types.hpp, decoded field by field. Only the component runtime knows the DDS
// types, so it is here; the CLI sees a port type and JSON.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include <dds/dds.h>
#include <nlohmann/json.hpp>

#include "component/port_types.hpp"

namespace rsca::component {

class SampleView {
public:
  virtual ~SampleView() = default;
  static std::unique_ptr<SampleView> of(port::PortType type);

  // The DDS type of the port type's topics.
  virtual const dds_topic_descriptor_t *descriptor() const = 0;
  // What `reader` has, `most` at most, each as JSON with the port value's fields
  // (timestamp_ns first; a PropertyEvent's value parsed when it is JSON).
  virtual std::vector<nlohmann::json> take(dds_entity_t reader, std::size_t most) = 0;
};

} // namespace rsca::component
