#include "control/endpoint.hpp"
#include "control/endpoint_impl.hpp"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "control.h" // generated from dds/control.idl
#include "control/partition_writers.hpp"
#include "control/worker_pool.hpp"
#include "protocol/addresses.hpp"
#include "protocol/codec.hpp"

namespace rsca::control {

using namespace detail;
using dds::Entity;

Expected<void> Endpoint::Impl::create_entities() {
  const dds_entity_t pp = participant->get();
  auto make = [](dds_entity_t handle, std::string_view what, Entity &into) -> Expected<void> {
    auto e = dds::checked(handle, what);
    if (!e)
      return tl::unexpected(e.error());
    into = std::move(*e);
    return {};
  };
  auto qos = control_qos();
  auto aqos = announcement_qos();
  std::vector<std::string> partitions{address};
  partitions.insert(partitions.end(), options.aliases.begin(), options.aliases.end());
  auto own_partition = partition_qos(partitions);
  Expected<void> ok =
      make(dds_create_topic(pp, &rsca_ctl_Request_desc, kRequestTopic, qos.get(), nullptr),
           "creating the request topic", request_topic)
          .and_then([&] {
            return make(dds_create_topic(pp, &rsca_ctl_Reply_desc, kReplyTopic, qos.get(), nullptr),
                        "creating the reply topic", reply_topic);
          })
          .and_then([&] {
            return make(dds_create_topic(pp, &rsca_ctl_Announcement_desc, kAnnouncementTopic,
                                         aqos.get(), nullptr),
                        "creating the announcement topic", announcement_topic);
          })
          .and_then([&] {
            return make(dds_create_subscriber(pp, own_partition.get(), nullptr),
                        "creating the subscriber", subscriber);
          })
          .and_then([&] {
            return make(
                dds_create_reader(subscriber.get(), request_topic.get(), qos.get(), nullptr),
                "creating the request reader", request_reader);
          })
          .and_then([&] {
            return make(dds_create_reader(subscriber.get(), reply_topic.get(), qos.get(), nullptr),
                        "creating the reply reader", reply_reader);
          })
          .and_then([&] { return make(dds_create_waitset(pp), "creating the waitset", waitset); })
          .and_then([&] {
            return make(dds_create_guardcondition(pp), "creating the guard condition", guard);
          });
  if (!ok)
    return ok;
  request_ways = std::make_unique<PartitionWriters>(pp, request_topic.get(), qos.get());
  reply_ways = std::make_unique<ReplyWays>(pp, reply_topic.get(), qos.get(), waitset.get());
  // Held requests stay in the reader, which wakes nobody until start_serving.
  serving = !options.hold_requests;
  dds_set_status_mask(request_reader.get(), serving ? DDS_DATA_AVAILABLE_STATUS : 0);
  dds_set_status_mask(reply_reader.get(), DDS_DATA_AVAILABLE_STATUS);
  dds_waitset_attach(waitset.get(), request_reader.get(), request_reader.get());
  dds_waitset_attach(waitset.get(), reply_reader.get(), reply_reader.get());
  dds_waitset_attach(waitset.get(), guard.get(), guard.get());
  if (!options.on_announcement)
    return {};
  // Announcements are not partitioned: whoever follows them sees every endpoint's.
  auto reader = make(dds_create_reader(pp, announcement_topic.get(), aqos.get(), nullptr),
                     "creating the announcement reader", announcement_reader);
  if (!reader)
    return reader;
  dds_set_status_mask(announcement_reader.get(), DDS_DATA_AVAILABLE_STATUS);
  dds_waitset_attach(waitset.get(), announcement_reader.get(), announcement_reader.get());
  return {};
}

void Endpoint::Impl::receive_loop() {
  while (!stopping.load()) {
    dds_duration_t timeout = DDS_SECS(1);
    {
      std::lock_guard lock(state_mutex);
      const auto now = Clock::now();
      if (!pending.empty())
        timeout = std::chrono::duration_cast<std::chrono::nanoseconds>(kDepartureCheck).count();
      if (replies_due)
        timeout = std::min<dds_duration_t>(
            timeout,
            std::max<dds_duration_t>(
                0,
                std::chrono::duration_cast<std::chrono::nanoseconds>(*replies_due - now).count()));
      for (const auto &[id, p] : pending)
        timeout = std::min<dds_duration_t>(
            timeout,
            std::max<dds_duration_t>(
                0, std::chrono::duration_cast<std::chrono::nanoseconds>(p.deadline - now).count()));
    }
    dds_waitset_wait(waitset.get(), nullptr, 0, timeout);
    bool triggered = false;
    dds_take_guardcondition(guard.get(), &triggered);
    if (serving)
      take_requests();
    take_replies();
    if (announcement_reader)
      take_announcements();
    expire_calls();
    fail_calls_to_departed();
    replies_due = reply_ways->flush();
  }
}

void Endpoint::Impl::take_requests() {
  void *samples[kTakeBatch] = {nullptr};
  dds_sample_info_t infos[kTakeBatch];
  for (;;) {
    const dds_return_t n = dds_take(request_reader.get(), samples, infos, kTakeBatch, kTakeBatch);
    if (n <= 0)
      return;
    for (dds_return_t i = 0; i < n; ++i) {
      if (!infos[i].valid_data)
        continue;
      const auto *r = static_cast<const rsca_ctl_Request *>(samples[i]);
      RequestContext context{str(r->id), str(r->sender), str(r->operation), str(r->target),
                             Clock::now()};
      if (context.target.empty())
        context.target = address;
      auto body = parse_body(r->body);
      handler_pool->post([this, context = std::move(context), body = std::move(body)]() mutable {
        serve(std::move(context), std::move(body));
      });
    }
    dds_return_loan(request_reader.get(), samples, n);
  }
}

// The calls of one batch, a result each: the relayed ones all started first, the others run one
// after another meanwhile, then the relayed ones waited for.
CallResult<Json> Endpoint::Impl::run_batch(const RequestContext &context, const Json &body) {
  auto calls = body.find("calls");
  if (calls == body.end() || !calls->is_array())
    return call_error(Status::BadRequest, "a batch needs \"calls\", an array");
  std::vector<RequestContext> items;
  std::vector<Json> bodies;
  std::vector<std::optional<std::future<CallResult<Json>>>> started;
  for (const auto &c : *calls) {
    RequestContext item{context.id, context.sender, c.value("operation", ""), c.value("target", ""),
                        context.received};
    bodies.push_back(c.value("body", Json::object()));
    started.push_back(item.operation == kBatch ? std::nullopt
                                               : served.start_relay(item, bodies.back()));
    items.push_back(std::move(item));
  }
  Json results = Json::array();
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (started[i]) {
      results.push_back(reply_json(served.finish(items[i].target, std::move(*started[i]))));
      continue;
    }
    results.push_back(reply_json(items[i].operation == kBatch
                                     ? call_error(Status::BadRequest, "batches do not nest")
                                     : served.dispatch(items[i], bodies[i])));
  }
  return Json{{"results", std::move(results)}};
}

namespace {

// The reply's bytes (protocol::kPayloadField), taken out of its JSON to travel beside it.
protocol::Bytes::container_type take_payload(CallResult<Json> &result) {
  if (!result || !result->is_object())
    return {};
  auto it = result->find(protocol::kPayloadField);
  if (it == result->end() || !it->is_binary())
    return {};
  auto bytes = std::move(it->get_binary());
  result->erase(it);
  return bytes;
}

// The reply's JSON text; one that cannot be text (a string that is not UTF-8) is a failure to
// report, not an exception on a worker thread.
std::string reply_text(CallResult<Json> &result) {
  if (result) {
    try {
      return result->dump();
    } catch (const Json::exception &e) {
      result = call_error(Status::Failed, fmt::format("the reply cannot be sent: {}", e.what()));
    }
  }
  return protocol::error_body(result.error());
}

} // namespace

void Endpoint::Impl::serve(RequestContext context, tl::expected<Json, std::string> body) {
  CallResult<Json> result =
      !body ? call_error(Status::BadRequest, fmt::format("the request body {}", body.error()))
      : context.operation == kBatch ? run_batch(context, *body)
                                    : served.dispatch(context, *body);
  auto payload = take_payload(result);
  std::string reply_body = reply_text(result);
  ReplyWays::Reply reply{
      context.id, static_cast<std::int32_t>(result ? Status::Ok : result.error().status),
      result ? std::string() : result.error().message, std::move(reply_body), std::move(payload)};
  // Sent, or held until the caller's reader comes: this thread goes on to the next request.
  if (auto sent = reply_ways->post(context.sender, std::move(reply)); !sent)
    if (auto unsaid = unsent_log.allow())
      spdlog::warn("{}: cannot reply to {} for {}: {}{}", address, context.sender,
                   context.operation, sent.error().message, LogLimiter::unsaid_note(*unsaid));
}

void Endpoint::Impl::take_replies() {
  void *samples[kTakeBatch] = {nullptr};
  dds_sample_info_t infos[kTakeBatch];
  for (;;) {
    const dds_return_t n = dds_take(reply_reader.get(), samples, infos, kTakeBatch, kTakeBatch);
    if (n <= 0)
      return;
    for (dds_return_t i = 0; i < n; ++i) {
      if (!infos[i].valid_data)
        continue;
      const auto *r = static_cast<const rsca_ctl_Reply *>(samples[i]);
      // A CLI client also reads the replies to the others (they share one way): not parsed.
      if (!is_call_of(address, r->id))
        continue;
      if (r->status != static_cast<std::int32_t>(Status::Ok)) {
        // A status this version does not know is a failure all the same, said as it came.
        auto error = protocol::is_known(r->status)
                         ? call_error(static_cast<Status>(r->status), str(r->error))
                         : call_error(Status::Failed,
                                      fmt::format("status {}: {}", r->status, str(r->error)));
        const Json error_body = parse_body(r->body).value_or(Json());
        error.value().details = protocol::details_of(error_body);
        error.value().maybe_received = protocol::maybe_received_of(error_body);
        complete(str(r->id), std::move(error));
        continue;
      }
      auto body = parse_body(r->body);
      if (!body) {
        complete(str(r->id), call_error(Status::Failed, fmt::format("the reply {}", body.error())));
        continue;
      }
      if (r->payload._length > 0 && body->is_object())
        (*body)[protocol::kPayloadField] = Json::binary(protocol::Bytes::container_type(
            r->payload._buffer, r->payload._buffer + r->payload._length));
      complete(str(r->id), std::move(*body));
    }
    dds_return_loan(reply_reader.get(), samples, n);
  }
}

Endpoint::Endpoint(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Expected<std::unique_ptr<Endpoint>> Endpoint::open(std::shared_ptr<dds::Participant> participant,
                                                   std::string address, EndpointOptions options) {
  auto invalid = [](const std::string &a) { return a.empty() || !protocol::is_plain_address(a); };
  for (const auto &a : options.aliases)
    if (invalid(a))
      return make_error({"control", 0, 0}, "address",
                        fmt::format("\"{}\" is not a valid endpoint address", a));
  if (invalid(address))
    return make_error({"control", 0, 0}, "address",
                      fmt::format("\"{}\" is not a valid endpoint address", address));
  auto impl = std::make_unique<Impl>();
  impl->participant = std::move(participant);
  impl->address = std::move(address);
  impl->options = options;
  if (auto ok = impl->create_entities(); !ok)
    return tl::unexpected(ok.error());
  impl->handler_pool = std::make_unique<WorkerPool>(std::max<std::size_t>(1, options.workers));
  impl->send_pool = std::make_unique<WorkerPool>(std::max<std::size_t>(1, options.senders));
  Impl *raw = impl.get();
  impl->receiver = std::thread([raw] { raw->receive_loop(); });
  return std::unique_ptr<Endpoint>(new Endpoint(std::move(impl)));
}

Endpoint::~Endpoint() {
  // The handlers under way first: they may still make calls, which need the sender and the
  // receiver. Stopped before them, a handler's call went to a sender already gone, or waited
  // for a reply nobody would take (ThreadSanitizer found the domain's handlers still running
  // while its daemon stopped).
  stop_serving();
  impl_->stopping = true;
  impl_->wake();
  impl_->receiver.join();
  impl_->send_pool.reset();
  impl_->handler_pool.reset();
  std::map<std::string, Impl::Pending> left;
  {
    std::lock_guard lock(impl_->state_mutex);
    left.swap(impl_->pending);
  }
  for (auto &[id, p] : left)
    p.promise.set_value(call_error(Status::Unavailable, "the endpoint is shutting down"));
}

const std::string &Endpoint::address() const {
  return impl_->address;
}

void Endpoint::on(const std::string &operation, Handler handler) {
  impl_->served.on(std::string(), operation, std::move(handler));
}

void Endpoint::on(const std::string &address, const std::string &operation, Handler handler) {
  impl_->served.on(address, operation, std::move(handler));
}

void Endpoint::relay(const std::string &address, RelayHandler handler) {
  impl_->served.relay(address, std::move(handler));
}

void Endpoint::stop_relaying(const std::string &address) {
  impl_->served.drop_relay(address);
}

void Endpoint::start_serving() {
  dds_set_status_mask(impl_->request_reader.get(), DDS_DATA_AVAILABLE_STATUS);
  impl_->serving = true;
  impl_->wake(); // takes what was held
}

void Endpoint::stop_serving() {
  dds_set_status_mask(impl_->request_reader.get(), 0);
  impl_->serving = false;
  // A request the receiver took just before is posted to the stopped pool and never runs: its
  // caller times out, as if this endpoint had gone a moment earlier.
  impl_->handler_pool->stop();
}

void Endpoint::stop_serving(const std::string &address) {
  impl_->served.drop(address);
}

void Endpoint::prepare(const std::string &target) {
  if (auto writer = impl_->request_ways->writer_for(impl_->route_of(target)); !writer)
    spdlog::debug("preparing the way to {}: {}", target, writer.error().message);
}

void Endpoint::prepare_replies(const std::string &caller) {
  if (auto writer = impl_->reply_ways->prepare(caller); !writer)
    spdlog::debug("preparing replies to {}: {}", caller, writer.error().message);
}

void Endpoint::forget(const std::string &target) {
  impl_->request_ways->erase(target);
  impl_->reply_ways->erase(target);
  std::lock_guard lock(impl_->routes_mutex);
  impl_->routes.erase(target);
}

} // namespace rsca::control
