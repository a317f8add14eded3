// ProcessLinks' parts, shared by its files: process_links.cpp (links to processes, relays, calls)
// and control_socket.cpp (the clients on the node's control socket). Nothing else includes it.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "common/log_limiter.hpp"
#include "control/link_socket.hpp"
#include "control/worker_pool.hpp"
#include "node/process_links.hpp"

namespace rsca::node {

namespace link = protocol::link;
using control::call_error;
using control::CallResult;
using control::Json;
using control::Status;

// How long a relayed request may take, at most: the longest a component operation is given
// (await_matched, a component's own configure) with room to spare. A dead process fails its
// requests at once, not at this bound.
inline constexpr std::chrono::seconds kRelayBound{60};
// A process's own call is given what it asks for, up to this.
inline constexpr std::chrono::seconds kCallBound{30};
// A client's (a CLI's launch waits six times its --timeout-ms), up to this.
inline constexpr std::chrono::hours kClientCallBound{1};
// Clients connected at once, at most: one more is closed at once.
inline constexpr std::size_t kMaxClients = 64;
// Calls one client has under way, at most: more are refused at once.
constexpr int kMaxClientCalls = 8;
// Threads that wait for clients' calls: apart from the processes' own, so that clients (a launch
// waits for minutes) never hold up a component's call.
inline constexpr std::size_t kClientCallThreads = 4;

// How long a client may stay connected with no call under way and no whole frame sent: 64 clients
// that connected and said nothing held every slot for ever (issue 37, defect 11). A CLI sends its
// hello at once, and a follower (`rsca logs -f`) calls twice a second.
inline constexpr std::chrono::seconds kClientIdle{5};

// One process the node started, and its link; or a client on the control socket (a CLI), which
// may only make calls.
struct LinkedProcess {
  pid_t pid = 0;
  bool client = false;
  process::Fd fd;
  std::unique_ptr<control::LinkWriter> writer;
  control::FrameReader reader;
  std::vector<std::string> addresses;
  std::set<std::string> announced;
  std::atomic<bool> ended{false};
  std::atomic<int> calls{0}; // a client's calls under way
  // When it connected, sent its last whole frame or was answered its last call: a client idle
  // since longer than kClientIdle, with no call under way, is closed.
  std::atomic<std::chrono::steady_clock::time_point> heard{std::chrono::steady_clock::now()};
  std::string why; // why it ended
};

struct ProcessLinks::Impl {
  control::Endpoint *endpoint = nullptr;
  HostData *host_data = nullptr;
  process::Fd epoll;
  process::Fd wake;
  process::Fd listener; // the control socket, when the node has one
  std::string listener_path;
  std::thread thread;
  std::unique_ptr<control::WorkerPool> outgoing;               // the processes' own calls
  std::unique_ptr<control::WorkerPool> client_calls;           // the clients'
  std::atomic<int> listener_fd{-1};                            // read by the poll thread
  std::chrono::steady_clock::time_point accept_paused_until{}; // poll thread only
  std::atomic<bool> stopping{false};
  LogLimiter refused_log; // clients refused: a flood of them writes a line per interval

  std::mutex mutex; // guards what follows
  std::map<pid_t, std::shared_ptr<LinkedProcess>> by_pid;
  std::map<int, std::shared_ptr<LinkedProcess>> by_fd; // processes and clients
  std::size_t clients = 0;
  std::map<std::string, std::shared_ptr<LinkedProcess>> by_address;
  struct Relayed {
    pid_t pid = 0;
    std::promise<CallResult<Json>> promise;
    std::chrono::steady_clock::time_point deadline;
    std::function<void(bool ok)> after; // runs with the reply's outcome, outside the lock
  };
  std::map<std::string, Relayed> relayed; // requests under way, by id
  std::uint64_t next_id = 0;
  bool closed = false;

  // Hands a request on to the process that serves its target; its reply to come.
  std::future<CallResult<Json>> relay(const Json &body, const control::RequestContext &context);
  // What the host's data makes of a relayed request on its way (a connect's ring), and what it
  // does once the reply is known.
  CallResult<Json> prepare(pid_t pid, const Json &body, const control::RequestContext &context,
                           std::function<void(bool ok)> &after);
  void complete(const std::string &id, pid_t pid, CallResult<Json> result);
  void expire();
  void poll_loop();
  void accept_clients();
  // Closes the clients idle past kClientIdle (see there). Poll thread only.
  void drop_idle_clients();
  // Out of descriptors, the listener stays readable: it leaves the poll for a second.
  void pause_accepting();
  void resume_accepting();
  void read(int fd);
  void take(const std::shared_ptr<LinkedProcess> &process, link::Frame frame);
  void make_call(const std::shared_ptr<LinkedProcess> &process, link::Request request);
  void announce(LinkedProcess &process, const link::Announce &a);
  // The link ended: its relayed requests fail, its announcements go. Called with the mutex held.
  void end(LinkedProcess &process, const std::string &why);
};

} // namespace rsca::node
