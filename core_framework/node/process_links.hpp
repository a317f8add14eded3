// The node's end of the links to the processes it started (protocol/node_link.hpp): the node as
// its host's agent for control. It serves each process's control addresses on the node's own
// endpoint and relays their requests over the link, makes the process's calls on DDS for it,
// and publishes its announcements. A process's death is seen at once as the end of its link.
// A relayed connect that asks for shared memory gets its ring from the host's data
// (node/host_data.hpp) on the way, and every end of a ring is let go when its process ends.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <sys/types.h>

#include "common/diagnostic.hpp"
#include "control/endpoint.hpp"
#include "node/host_data.hpp"
#include "process/fd.hpp"

namespace rsca::node {

class ProcessLinks {
public:
  // Relays through `endpoint`, which must outlive close(); rings from `host_data` (may be null:
  // no same-host connections), which must outlive this.
  static Expected<std::unique_ptr<ProcessLinks>> start(control::Endpoint &endpoint,
                                                       HostData *host_data = nullptr);
  ~ProcessLinks();
  ProcessLinks(const ProcessLinks &) = delete;
  ProcessLinks &operator=(const ProcessLinks &) = delete;

  // Takes the node's end of the link of process `pid`, which serves `addresses`: from now on
  // the node serves them and relays to it. Requests that come before the process reads its link
  // wait in the socket.
  void attach(pid_t pid, process::Fd link, std::vector<std::string> addresses);
  // The process has exited and been reaped: its addresses are served no longer.
  void detach(pid_t pid);
  // Listens at `path` (control/link_socket.hpp) for local clients: each connection is a link
  // over which the client makes calls, which the node makes on DDS for it (a CLI thus needs no
  // DDS participant of its own, and the daemons see no participant come and go per command). A
  // client may not announce, withdraw or route; at most 64 are connected at once. The socket
  // file goes with close().
  Expected<void> listen(const std::string &path);
  // Stops relaying (calls under way fail) and lets go of the endpoint; attach and detach do
  // nothing afterwards. The destructor does it.
  void close();

  struct Impl;

private:
  explicit ProcessLinks(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

} // namespace rsca::node
