// The control plane: every rsca process (domain daemon, node daemons, components, the CLI) owns
// one Endpoint, named by an address. Requests to an address are written into the DDS partition
// of that name, so only the addressed process receives them; replies go back into the sender's
// partition. Every call has a deadline. Handlers run on worker threads, never on the thread that
// takes samples, so a handler may itself call other endpoints and wait.
//
// One endpoint may serve more addresses than its own (aliases): a component host serves each of
// its components at the component's address. A caller that knows which endpoint serves an
// address (route) writes to that endpoint's partition, and call_all sends all calls for the
// addresses of one endpoint as one request: a host of a hundred components costs one DDS reader,
// one writer per caller and one round trip per step of a launch, not a hundred.
#pragma once

#include <chrono>
#include <functional>
#include <future>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <tl/expected.hpp>

#include "common/diagnostic.hpp"
#include "control/caller.hpp"
#include "control/handler_table.hpp"
#include "control/server.hpp"
#include "dds/participant.hpp"
#include "protocol/status.hpp"

namespace rsca::control {

using Json = nlohmann::json;

// Why a call failed: the runtime error type (protocol/status.hpp), used under these names here.
using protocol::call_error;
using protocol::CallError;
using protocol::CallResult;
using protocol::Status;
using protocol::to_string;

// An endpoint's announcement as others see it.
struct AnnouncementEvent {
  enum class Kind : std::uint8_t { Alive, Gone };
  Kind kind = Kind::Alive;
  std::string address;
  std::string endpoint_kind; // "node", "component", "domain"; empty when Gone
  Json body;                 // empty when Gone
  // Gone: withdrawn by its announcer (it stopped), not lost with its DDS lease (it died, or is
  // cut off: which, nobody can tell from here).
  bool withdrawn = false;
};
using AnnouncementHandler = std::function<void(const AnnouncementEvent &)>;

using RelayHandler =
    std::function<std::future<CallResult<Json>>(const Json &body, const RequestContext &context)>;

struct EndpointOptions {
  std::size_t workers = 8; // threads that run request handlers
  std::size_t senders = 4; // threads that write requests, so callers never wait on discovery
  // Follows every endpoint's announcements when set: called for each change on the receiving
  // thread, so it must not block. Given at open so that no announcement arrives before it.
  AnnouncementHandler on_announcement;
  // More addresses this endpoint serves, fixed at open (a DDS partition each).
  std::vector<std::string> aliases;
  // Announced endpoints of these kinds get their way prepared (see prepare) as soon as they are
  // announced: the first call to a node then does not wait for DDS to match a new writer.
  std::vector<std::string> prepare_kinds;
  // Requests wait, unread, until start_serving(): a daemon that registers its handlers (and
  // restores its state) after open never answers a request that came in between with "does not
  // serve" (a CLI calling a domain daemon that is restarting).
  bool hold_requests = false;
};

class Endpoint final : public Server {
public:
  static Expected<std::unique_ptr<Endpoint>> open(std::shared_ptr<dds::Participant> participant,
                                                  std::string address,
                                                  EndpointOptions options = {});
  // Closes: running handlers finish and write their replies, then the endpoint's DDS entities
  // go. Cyclone lingers a deleted reliable writer until its data is acknowledged (bounded by
  // WriterLingerDuration), so the last replies still reach their callers.
  ~Endpoint() override;
  Endpoint(const Endpoint &) = delete;
  Endpoint &operator=(const Endpoint &) = delete;

  const std::string &address() const override;

  // Serves `operation` at every address of the endpoint; a later registration replaces an
  // earlier one.
  void on(const std::string &operation, Handler handler) override;
  // Serves `operation` at `address` (its own or an alias) only, before any handler of
  // on(operation).
  void on(const std::string &address, const std::string &operation, Handler handler) override;
  // Serves every operation at `address` by handing it on (a node, to the process it started):
  // the handler starts the call and returns its result to come, and must not block. In a batch,
  // every relayed call starts before any is waited for, so the processes behind a node work on
  // their parts at once.
  void relay(const std::string &address, RelayHandler handler);
  // No more relays to `address`; calls under way are not waited for (they end on their own).
  void stop_relaying(const std::string &address);
  // Serves the requests held since open (EndpointOptions::hold_requests) and those that follow.
  void start_serving();
  // Drops the handlers of `address` and returns once none of them is running any more.
  void stop_serving(const std::string &address) override;
  // Takes no more requests and returns once the handlers under way have returned; calls still
  // work. The destructor does it first. An owner whose handlers reach the endpoint through a
  // pointer calls it before clearing the pointer.
  void stop_serving();

  // A call fails at its deadline (Timeout), at once when nobody serves `target` by then
  // (Unavailable), or as soon as its addressee leaves DDS after it was sent (Unavailable,
  // maybe_received): it exited or lost its lease, and will not reply.
  std::future<CallResult<Json>> call(const std::string &target, const std::string &operation,
                                     Json body, std::chrono::milliseconds timeout) override;
  // Makes every call at once and waits for all; each result in the order of the calls. Calls to
  // addresses routed through the same endpoint travel as one request ("endpoint.batch"), whose
  // handlers run one after another.
  std::vector<CallResult<Json>> call_all(const std::vector<Call> &calls,
                                         std::chrono::milliseconds timeout) override;

  // Calls to `target` go to `via`, the endpoint that serves it as an alias.
  void route(const std::string &target, const std::string &via) override;

  // Creates the way to `target` ahead of the first call, so that DDS discovery of an endpoint
  // that is about to appear overlaps with whatever happens before that call.
  void prepare(const std::string &target) override;
  // The same for the replies to `caller` (the domain, for a node or component), whose first
  // call then does not wait for DDS to match a new reply writer.
  void prepare_replies(const std::string &caller) override;
  // Fails every call to `target` under way, saying `why`: its caller knows the addressee is dead
  // (its node saw it exit) sooner than DDS would (the addressee's lease).
  void abandon(const std::string &target, const std::string &why);
  // Drops the way to and from `target` (an endpoint that is gone for good), and its route.
  void forget(const std::string &target) override;

  // Publishes (or updates) this endpoint's announcement; `withdraw` removes it.
  Expected<void> announce(const std::string &kind, const Json &body);
  void withdraw();
  // The same for one of its aliases.
  Expected<void> announce(const std::string &alias, const std::string &kind,
                          const Json &body) override;
  void withdraw(const std::string &alias) override;

  struct Impl;

private:
  explicit Endpoint(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

} // namespace rsca::control
