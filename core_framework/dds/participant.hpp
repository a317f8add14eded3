// A DDS domain participant joined with the project's configuration. One process may hold several
// (tests do); the Cyclone domain they share is created on first use and lives while any does.
#pragma once

#include <memory>

#include "dds/dds_settings.hpp"
#include "dds/entity.hpp"

namespace rsca::dds {

class Participant {
public:
  static Expected<std::shared_ptr<Participant>> create(const DdsSettings &settings);

  dds_entity_t get() const { return participant_.get(); }
  const DdsSettings &settings() const { return settings_; }

  Participant(std::shared_ptr<Entity> domain, Entity participant, DdsSettings settings)
      : domain_(std::move(domain)), participant_(std::move(participant)),
        settings_(std::move(settings)) {}

private:
  std::shared_ptr<Entity> domain_; // declared first: destroyed after the participant
  Entity participant_;
  DdsSettings settings_;
};

} // namespace rsca::dds
