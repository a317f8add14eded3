// The CLI's connection to the domain, a timeout on every call, and the mapping of failures to exit
// codes and messages. The connection is a link to a node on this host, over the node's control
// socket (the node makes the calls on DDS for it), when one is found; else a DDS participant and
// control endpoint of the CLI's own.
#pragma once

#include <chrono>
#include <filesystem>
#include <functional>
#include <future>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "commands.hpp"
#include "control/operation.hpp"
#include "control/server.hpp"
#include "dds/participant.hpp"
#include "exit_codes.hpp"
#include "protocol/addresses.hpp"

namespace rsca::cli {

class DomainClient {
public:
  static Expected<DomainClient> connect(const GlobalOptions &global);

  struct Link {
    std::shared_ptr<control::Server> server;
    std::string socket;
  };

  template <control::Operation Op>
  control::CallResult<typename Op::Reply> call(const typename Op::Request &request,
                                               std::chrono::milliseconds timeout) const {
    return control::call<Op>(*server_, protocol::domain_address(domain_), request, timeout);
  }
  // A call the CLI does other things while it waits for (a launch, whose progress it shows): its
  // reply is read with control::reply_of<Op>.
  template <control::Operation Op>
  std::future<control::CallResult<control::Json>>
  call_async(const typename Op::Request &request, std::chrono::milliseconds timeout) const {
    return call_async_at<Op>(protocol::domain_address(domain_), request, timeout);
  }
  // A call to another party than the domain (a node, whose address domain.nodes gives): through
  // the same link or endpoint.
  template <control::Operation Op>
  std::future<control::CallResult<control::Json>>
  call_async_at(const std::string &address, const typename Op::Request &request,
                std::chrono::milliseconds timeout) const {
    return server_->call(address, std::string(Op::name), protocol::encode(request), timeout);
  }
  const std::string &domain() const { return domain_; }
  // The node's control socket the calls go through; empty when they go over DDS.
  const std::string &via_socket() const { return socket_; }

private:
  std::shared_ptr<dds::Participant> participant_; // over DDS only
  std::shared_ptr<control::Server> server_;
  std::string domain_;
  std::string socket_;
};

// Where `rsca domain up` keeps a local domain's pid files, logs and node sockets: $RSCA_RUN_DIR,
// else a folder per user and DDS domain id in the temporary folder.
std::filesystem::path default_run_dir();
// The node control sockets the CLI tries, in order: $RSCA_NODE_SOCKET (a path; "none": use DDS),
// else the sockets of the local domain's nodes (default_run_dir()/*.sock).
std::vector<std::filesystem::path> node_sockets();

int exit_code_of(control::Status status);
// Prints a failed call (text or JSON) and returns its exit code.
int report_failure(const GlobalOptions &global, const std::string &what,
                   const control::CallError &error);
// A failure the CLI finds itself: "rsca WHAT: MESSAGE" on stderr, or with --json the error
// object every command prints, {"error": {"status", "message"}, "exit": CODE}. Returns `code`.
int fail(const GlobalOptions &global, std::string_view what, int code, const std::string &message);
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
    return fail(global, what, kFailed, client.error().to_string());
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
