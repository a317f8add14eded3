// The CLI's connection to the domain: its own DDS participant and control endpoint, a timeout on
// every call, and the mapping of failures to exit codes and messages.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "control/endpoint.hpp"

namespace rsca::cli {

struct GlobalOptions;

class DomainClient {
public:
  static Expected<DomainClient> connect(const GlobalOptions &global);

  control::CallResult<control::Json> call(const std::string &operation, control::Json body,
                                          std::chrono::milliseconds timeout) const;
  std::future<control::CallResult<control::Json>>
  call_async(const std::string &operation, control::Json body,
             std::chrono::milliseconds timeout) const;
  const std::string &domain() const { return domain_; }

private:
  std::shared_ptr<dds::Participant> participant_;
  std::shared_ptr<control::Endpoint> endpoint_;
  std::string domain_;
};

int exit_code_of(control::Status status);
// Prints a failed call (text or JSON) and returns its exit code.
int report_failure(const GlobalOptions &global, const std::string &what,
                   const control::CallError &error);
// Prints a reply as JSON.
void print_json(const control::Json &value);

} // namespace rsca::cli
