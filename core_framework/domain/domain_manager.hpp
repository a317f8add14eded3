// DomainManager: the domain daemon's state and the operations it serves — nodes and devices
// (from their announcements), installed applications (one ApplicationFactory each, persisted),
// running applications — and what it does when a node or component goes away.
#pragma once

#include <chrono>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "allocator/resource_allocator.hpp"
#include "control/endpoint.hpp"
#include "domain/application_factory.hpp"
#include "domain/component_registry.hpp"
#include "domain/delivered_code.hpp"
#include "domain/domain_store.hpp"

namespace rsca::domain {

struct DomainOptions {
  std::string name = "rsca";        // the DMD's name
  std::filesystem::path repository; // installed profiles are kept here
  // Where code an SPD names that its install did not carry is found, by file name (executables;
  // libraries also in the lib folder beside each): rsca's own component folders.
  std::vector<std::filesystem::path> exec_path;
  CodeDelivery delivery = CodeDelivery::Stripped; // what nodes get of code files (file_manager.hpp)
  std::chrono::milliseconds registration_timeout{10000};
  std::chrono::milliseconds call_timeout{5000};
  allocator::Strategy strategy = allocator::Strategy::Pack; // placement, unless a launch says
};

class DomainManager {
public:
  static Expected<std::unique_ptr<DomainManager>>
  create(std::shared_ptr<dds::Participant> participant, DomainOptions options);
  ~DomainManager();

  struct Impl;

private:
  explicit DomainManager(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

} // namespace rsca::domain
