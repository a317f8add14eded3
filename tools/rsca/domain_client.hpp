// The CLI's connection to the domain: its own DDS participant and control endpoint, a timeout on
// every call, and the mapping of failures to exit codes and messages.
#pragma once

#include <chrono>
#include <functional>
#include <future>
#include <memory>
#include <string>

#include <fmt/format.h>

#include "commands.hpp"
#include "control/endpoint.hpp"
#include "control/operation.hpp"
#include "exit_codes.hpp"
#include "protocol/addresses.hpp"

namespace rsca::cli {

class DomainClient {
public:
  static Expected<DomainClient> connect(const GlobalOptions &global);

  template <control::Operation Op>
  control::CallResult<typename Op::Reply> call(const typename Op::Request &request,
                                               std::chrono::milliseconds timeout) const {
    return control::call<Op>(*endpoint_, protocol::domain_address(domain_), request, timeout);
  }
  // A call the CLI does other things while it waits for (a launch, whose progress it shows): its
  // reply is read with control::reply_of<Op>.
  template <control::Operation Op>
  std::future<control::CallResult<control::Json>>
  call_async(const typename Op::Request &request, std::chrono::milliseconds timeout) const {
    return endpoint_->call(protocol::domain_address(domain_), std::string(Op::name),
                           protocol::encode(request), timeout);
  }
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

// Connects, calls `Op` and prints its reply: as JSON with --json, else with `print_text`. The
// exit code.
template <control::Operation Op>
int call_and_print(const GlobalOptions &global, const std::string &what,
                   const typename Op::Request &request, std::chrono::milliseconds timeout,
                   const std::function<void(const typename Op::Reply &)> &print_text) {
  auto client = DomainClient::connect(global);
  if (!client) {
    fmt::print(stderr, "rsca {}: {}\n", what, client.error().to_string());
    return kFailed;
  }
  auto reply = client->call<Op>(request, timeout);
  if (!reply)
    return report_failure(global, what, reply.error());
  if (global.json)
    print_json(protocol::encode(*reply));
  else
    print_text(*reply);
  return kOk;
}

} // namespace rsca::cli
