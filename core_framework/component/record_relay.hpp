// The conversion between a same-host ring's records (component/port_record.hpp) and the typed
// DDS samples of dds/ports.idl, for the node's relay of a ring to and from other hosts
// (node/topic_bridge.hpp). Only the component runtime knows both forms, so it is here; the node
// sees a port type and bytes.
#pragma once

#include <cstddef>
#include <memory>

#include <dds/dds.h>

#include "component/port_types.hpp"
#include "shm/ring.hpp"

namespace rsca::component {

class RecordRelay {
public:
  virtual ~RecordRelay() = default;
  static std::unique_ptr<RecordRelay> of(port::PortType type);

  // The DDS type of the port type's topics.
  virtual const dds_topic_descriptor_t *descriptor() const = 0;
  // Every record `ring` has for its reader, each written on the DDS `writer`. Returns how many;
  // one that does not decode, or that a writer overwrote while it was read, is dropped.
  virtual std::size_t to_dds(shm::RingReader &ring, dds_entity_t writer) = 0;
  // Every sample the DDS `reader` has, each written to `ring`, except those of the publication
  // `own` (the node's own writer on the topic: what it sent is not relayed back in). Returns how
  // many; a sample too large for the ring is dropped.
  virtual std::size_t from_dds(dds_entity_t reader, dds_instance_handle_t own,
                               shm::RingWriter &ring) = 0;
};

} // namespace rsca::component
