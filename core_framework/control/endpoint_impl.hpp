// The endpoint's private parts, shared by its files: endpoint.cpp (entities, the receive thread,
// serving requests), endpoint_calls.cpp (calls made and their ends) and
// endpoint_announcements.cpp. Nothing outside control/ includes it.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "control/announcement_slots.hpp"
#include "control/endpoint.hpp"
#include "control/handler_table.hpp"
#include "control/partition_writers.hpp"
#include "control/reply_ways.hpp"
#include "control/worker_pool.hpp"
#include "dds/entity.hpp"
#include "protocol/json_text.hpp"
#include "protocol/topics.hpp"

namespace rsca::control {
using Clock = std::chrono::steady_clock;

namespace detail {

using protocol::kAnnouncementTopic;
using protocol::kReplyTopic;
using protocol::kRequestTopic;
inline constexpr std::uint32_t kTakeBatch = 64;
// How often the receive thread looks, while calls are under way, for addressees that left DDS.
inline constexpr auto kDepartureCheck = std::chrono::milliseconds(200);

inline dds::Qos control_qos() {
  auto qos = dds::make_qos();
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, 0);
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  return qos;
}

inline dds::Qos announcement_qos() {
  auto qos = dds::make_qos();
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, 1);
  dds_qset_durability(qos.get(), DDS_DURABILITY_TRANSIENT_LOCAL);
  return qos;
}

inline dds::Qos partition_qos(const std::vector<std::string> &partitions) {
  auto qos = dds::make_qos();
  std::vector<const char *> names;
  for (const auto &p : partitions)
    names.push_back(p.c_str());
  dds_qset_partition(qos.get(), static_cast<std::uint32_t>(names.size()), names.data());
  return qos;
}

inline constexpr const char *kBatch = "endpoint.batch";

inline Json reply_json(const CallResult<Json> &result) {
  if (result)
    return Json{{"status", 0}, {"body", *result}};
  Json reply{{"status", static_cast<std::int32_t>(result.error().status)},
             {"error", result.error().message}};
  if (!result.error().details.empty())
    reply["details"] = result.error().details;
  return reply;
}

inline CallResult<Json> result_of(const Json &reply) {
  const auto status = reply.value("status", static_cast<std::int32_t>(Status::Failed));
  if (status == static_cast<std::int32_t>(Status::Ok))
    return reply.value("body", Json::object());
  const auto error = reply.value("error", std::string("no reason given"));
  auto failed = protocol::is_known(status)
                    ? call_error(static_cast<Status>(status), error)
                    : call_error(Status::Failed, fmt::format("status {}: {}", status, error));
  failed.value().details = protocol::details_of(reply);
  return failed;
}

// A body that came over DDS, untrusted: its value (none is {}), or why it is refused
// (protocol/json_text.hpp: not JSON, or nested too deep to be copied safely).
inline tl::expected<Json, std::string> parse_body(const char *text) {
  if (text == nullptr || *text == '\0')
    return Json::object();
  return protocol::parse_json(text);
}

// A call's id: "<caller's address>#<sequence>", unique per caller.
inline std::string call_id(const std::string &caller, std::uint64_t sequence) {
  return fmt::format("{}#{}", caller, sequence);
}

inline bool is_call_of(const std::string &caller, const char *id) {
  const std::string_view text = id != nullptr ? id : "";
  return text.size() > caller.size() && text.compare(0, caller.size(), caller) == 0 &&
         text[caller.size()] == '#';
}

inline std::string str(const char *text) {
  return text != nullptr ? std::string(text) : std::string();
}

} // namespace detail

struct Endpoint::Impl {
  struct Pending {
    std::promise<CallResult<Json>> promise;
    Clock::time_point deadline;
    std::string target;
    std::string operation;
    bool sent = false; // the addressee was found: silence is a timeout
  };

  std::shared_ptr<dds::Participant> participant;
  std::string address;
  EndpointOptions options;

  dds::Entity request_topic, reply_topic, announcement_topic;
  dds::Entity subscriber; // in this endpoint's partition
  dds::Entity request_reader, reply_reader, announcement_reader;
  dds::Entity waitset, guard;
  dds::Entity announcement_writer;
  std::mutex announcement_mutex; // guards announcement_writer and announcer_slots
  AnnouncerSlots announcer_slots;
  HeardSlots heard_slots; // receive thread only

  std::unique_ptr<PartitionWriters> request_ways;
  std::unique_ptr<ReplyWays> reply_ways;
  std::optional<Clock::time_point> replies_due; // receive thread only: a held reply's deadline
  LogLimiter unsent_log;                        // replies that have no way to their caller
  std::mutex routes_mutex;
  std::map<std::string, std::string> routes; // target → the endpoint that serves it
  Clock::time_point departures_checked;      // receive thread only

  std::mutex state_mutex;
  HandlerTable served;
  std::map<std::string, Pending> pending;
  std::uint64_t next_id = 0;

  std::atomic<bool> stopping{false};
  std::atomic<bool> serving{false}; // requests are taken (see EndpointOptions::hold_requests)
  std::unique_ptr<WorkerPool> handler_pool; // runs request handlers
  std::unique_ptr<WorkerPool> send_pool;    // writes requests, so callers never wait on discovery
  std::thread receiver;

  Expected<void> create_entities();
  void receive_loop();
  // Fails, at once, every pending call for which `failure` gives an error.
  void fail_calls(const std::function<std::optional<CallError>(const Pending &)> &failure);
  void take_requests();
  void take_replies();
  void take_announcements();
  void expire_calls();
  void fail_calls_to_departed();
  void serve(RequestContext context, tl::expected<Json, std::string> body);

  CallResult<Json> run_batch(const RequestContext &context, const Json &body);
  std::string route_of(const std::string &target);
  Expected<void> announce(const std::string &as, const std::string &kind, const Json &body);
  void withdraw(const std::string &as);
  void send_request(std::string id, std::string target, std::string operation, std::string body);
  void complete(const std::string &id, CallResult<Json> result);
  void wake() { dds_set_guardcondition(guard.get(), true); }
};

} // namespace rsca::control
