// The node link: the control channel between a node daemon (the host's agent) and a process it
// started. The node hands the process one end of a Unix stream socket pair as descriptor
// kNodeLinkFd, named in the environment (kNodeLinkVariable). Everything the process would say on
// the DDS control plane travels over it instead, and the node says it on DDS for the process:
// - the node relays requests addressed to the process's control addresses (Request down, Reply
//   up), and the process's own calls (Request up, Reply down), so the process needs no DDS
//   participant for control, and a launch step is one DDS request per node;
// - the process announces and withdraws its addresses through the node (Announce, Withdraw);
// - the process tells the node which endpoint serves an address it calls (Route).
// Each frame is a 4-byte big-endian length followed by that many bytes of JSON: one object with
// exactly one key, the frame's kind, whose value is the message below. A frame is at most
// kMaxLinkFrame bytes; a longer one, or one that does not decode, ends the link.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <variant>

#include "protocol/codec.hpp"

namespace rsca::protocol::link {

inline constexpr int kNodeLinkFd = 3;
inline constexpr const char *kNodeLinkVariable = "RSCA_NODE_LINK_FD";
inline constexpr std::uint32_t kMaxLinkFrame = 16U << 20U;

// A request the node's link answers itself, at once, with {"node": its address}: a local client
// (the CLI) asks it before relying on a node, since a hung node's socket still accepts.
inline constexpr const char *kHelloTarget = "";
inline constexpr const char *kHelloOperation = "link.hello";

// A call, either way: from the node, one addressed to the process (target is one of its
// addresses); from the process, one it makes (the node makes it on DDS).
struct Request {
  std::string id; // unique among the sender's requests under way
  std::string target;
  std::string operation;
  std::string sender;          // the caller's address
  std::int64_t timeout_ms = 0; // how long the caller waits; the other side bounds it too
  Json body = Json::object();
  static constexpr auto fields() {
    using R = Request;
    return std::tuple{required("id", &R::id),
                      required("target", &R::target),
                      required("operation", &R::operation),
                      required("sender", &R::sender),
                      required("timeout_ms", &R::timeout_ms),
                      required("body", &R::body)};
  }
};

// The answer to a Request: status 0 (protocol/status.hpp's Ok) with its body, or an error with
// its message and details.
struct Reply {
  std::string id;
  std::int32_t status = 0;
  std::string error;
  Json body = Json::object(); // on error: {"details": [...]} (protocol/status.hpp)
  static constexpr auto fields() {
    using R = Reply;
    return std::tuple{required("id", &R::id), required("status", &R::status),
                      required("error", &R::error), required("body", &R::body)};
  }
};

// The process announces one of its addresses (again at each change); the node publishes it.
struct Announce {
  std::string address;
  std::string kind; // "component", "host"
  Json body = Json::object();
  static constexpr auto fields() {
    using R = Announce;
    return std::tuple{required("address", &R::address), required("kind", &R::kind),
                      required("body", &R::body)};
  }
};

struct Withdraw {
  std::string address;
  static constexpr auto fields() { return std::tuple{required("address", &Withdraw::address)}; }
};

// Calls the process makes to `target` go to `via`, the endpoint that serves it.
struct Route {
  std::string target;
  std::string via;
  static constexpr auto fields() {
    return std::tuple{required("target", &Route::target), required("via", &Route::via)};
  }
};

using Frame = std::variant<Request, Reply, Announce, Withdraw, Route>;

// A frame as the JSON object that carries it, and back (a clear error naming the field).
Json encode_frame(const Frame &frame);
tl::expected<Frame, std::string> decode_frame(const Json &json);

} // namespace rsca::protocol::link
