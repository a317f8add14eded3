// The control presence of a process its node daemon started (protocol/node_link.hpp): requests
// to its addresses come from the node over the inherited socket, its calls and announcements go
// to the node, which makes them on DDS. The process needs no DDS participant for control: it
// joins DDS only when a data connection of its own asks for it.
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "control/server.hpp"
#include "process/fd.hpp"

namespace rsca::control {

class NodeLink final : public Server {
public:
  // The link the node handed this process (kNodeLinkVariable names its descriptor), taken over
  // and cleared from the environment, so a process this one starts does not take it too. None
  // when the process was not started by a node (by hand, or by a test).
  static std::optional<process::Fd> inherited();
  // Serves `address` (and whatever else is served through it) over `link`.
  static Expected<std::unique_ptr<NodeLink>> open(process::Fd link, std::string address,
                                                  std::size_t workers = 4);
  // Running handlers finish and send their replies; calls under way fail.
  ~NodeLink() override;
  NodeLink(const NodeLink &) = delete;
  NodeLink &operator=(const NodeLink &) = delete;

  const std::string &address() const override;
  void on(const std::string &operation, Handler handler) override;
  void on(const std::string &address, const std::string &operation, Handler handler) override;
  void stop_serving(const std::string &address) override;
  std::future<CallResult<Json>> call(const std::string &target, const std::string &operation,
                                     Json body, std::chrono::milliseconds timeout) override;
  std::vector<CallResult<Json>> call_all(const std::vector<Call> &calls,
                                         std::chrono::milliseconds timeout) override;
  void route(const std::string &target, const std::string &via) override;
  void prepare(const std::string &) override {}         // the node's way is made already
  void forget(const std::string &) override {}          // the node keeps no way per target
  void prepare_replies(const std::string &) override {} // replies go back over the link
  Expected<void> announce(const std::string &address, const std::string &kind,
                          const Json &body) override;
  void withdraw(const std::string &address) override;

  struct Impl;

private:
  explicit NodeLink(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

} // namespace rsca::control
