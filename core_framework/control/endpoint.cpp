#include "control/endpoint.hpp"

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

namespace rsca::control {

std::string_view to_string(Status status) {
  switch (status) {
  case Status::Ok:
    return "ok";
  case Status::BadRequest:
    return "bad request";
  case Status::NotFound:
    return "not found";
  case Status::Failed:
    return "failed";
  case Status::Timeout:
    return "timeout";
  case Status::Unavailable:
    return "unavailable";
  case Status::Rejected:
    return "rejected";
  }
  return "unknown";
}

namespace {

using Clock = std::chrono::steady_clock;
using dds::Entity;

constexpr const char *kRequestTopic = "rsca_ctl_Request";
constexpr const char *kReplyTopic = "rsca_ctl_Reply";
constexpr const char *kAnnouncementTopic = "rsca_ctl_Announcement";
constexpr std::uint32_t kTakeBatch = 64;
// How often the receive thread looks, while calls are under way, for addressees that left DDS.
constexpr auto kDepartureCheck = std::chrono::milliseconds(200);

dds::Qos control_qos() {
  auto qos = dds::make_qos();
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, 0);
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  return qos;
}

dds::Qos announcement_qos() {
  auto qos = dds::make_qos();
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, 1);
  dds_qset_durability(qos.get(), DDS_DURABILITY_TRANSIENT_LOCAL);
  return qos;
}

dds::Qos partition_qos(const std::vector<std::string> &partitions) {
  auto qos = dds::make_qos();
  std::vector<const char *> names;
  for (const auto &p : partitions)
    names.push_back(p.c_str());
  dds_qset_partition(qos.get(), static_cast<std::uint32_t>(names.size()), names.data());
  return qos;
}

constexpr const char *kBatch = "endpoint.batch";

Json reply_json(const CallResult<Json> &result) {
  if (result)
    return Json{{"status", 0}, {"body", *result}};
  return Json{{"status", static_cast<std::int32_t>(result.error().status)},
              {"error", result.error().message}};
}

CallResult<Json> result_of(const Json &reply) {
  const auto status = static_cast<Status>(reply.value("status", 3));
  if (status != Status::Ok)
    return call_error(status, reply.value("error", std::string("no reason given")));
  return reply.value("body", Json::object());
}

// Runs a handler. A request is untrusted: a handler that reads a field of the wrong type (JSON's
// type errors) answers BadRequest instead of ending the process.
CallResult<Json> run_handler(const Handler &handler, const Json &body,
                             const RequestContext &context) {
  try {
    return handler(body, context);
  } catch (const Json::exception &e) {
    return call_error(Status::BadRequest,
                      fmt::format("malformed \"{}\" request: {}", context.operation, e.what()));
  }
}

Json parse_body(const char *text) {
  if (text == nullptr || *text == '\0')
    return Json::object();
  return Json::parse(text, nullptr, /*allow_exceptions=*/false);
}

std::string str(const char *text) {
  return text != nullptr ? std::string(text) : std::string();
}

} // namespace

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

  Entity request_topic, reply_topic, announcement_topic;
  Entity subscriber; // in this endpoint's partition
  Entity request_reader, reply_reader, announcement_reader;
  Entity waitset, guard;
  Entity announcement_writer;
  std::mutex announcement_mutex; // guards announcement_writer

  std::unique_ptr<PartitionWriters> request_ways, reply_ways;
  std::mutex routes_mutex;
  std::map<std::string, std::string> routes; // target → the endpoint that serves it
  Clock::time_point departures_checked;      // receive thread only

  std::mutex state_mutex;
  std::map<std::pair<std::string, std::string>, Handler> handlers; // (address or "", operation)
  std::map<std::string, int> running;                              // handlers running, by address
  std::condition_variable handler_done;
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
  void serve(RequestContext context, Json body);
  CallResult<Json> dispatch(const RequestContext &context, const Json &body);
  CallResult<Json> run_batch(const RequestContext &context, const Json &body);
  std::string route_of(const std::string &target);
  Expected<void> announce(const std::string &as, const std::string &kind, const Json &body);
  void withdraw(const std::string &as);
  void send_request(std::string id, std::string target, std::string operation, std::string body);
  void complete(const std::string &id, CallResult<Json> result);
  void wake() { dds_set_guardcondition(guard.get(), true); }
};

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
  reply_ways = std::make_unique<PartitionWriters>(pp, reply_topic.get(), qos.get());
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
      Json body = parse_body(r->body);
      handler_pool->post([this, context = std::move(context), body = std::move(body)]() mutable {
        serve(std::move(context), std::move(body));
      });
    }
    dds_return_loan(request_reader.get(), samples, n);
  }
}

// Runs the handler for the request's address and operation. stop_serving waits for it.
CallResult<Json> Endpoint::Impl::dispatch(const RequestContext &context, const Json &body) {
  Handler handler;
  {
    std::lock_guard lock(state_mutex);
    auto it = handlers.find({context.target, context.operation});
    if (it == handlers.end())
      it = handlers.find({std::string(), context.operation});
    if (it == handlers.end())
      return call_error(Status::BadRequest, fmt::format("{} does not serve operation \"{}\"",
                                                        context.target, context.operation));
    handler = it->second;
    ++running[context.target];
  }
  CallResult<Json> result = run_handler(handler, body, context);
  {
    std::lock_guard lock(state_mutex);
    if (--running[context.target] == 0)
      running.erase(context.target);
  }
  handler_done.notify_all();
  return result;
}

// The calls of one batch, one after another; a result each.
CallResult<Json> Endpoint::Impl::run_batch(const RequestContext &context, const Json &body) {
  auto calls = body.find("calls");
  if (calls == body.end() || !calls->is_array())
    return call_error(Status::BadRequest, "a batch needs \"calls\", an array");
  Json results = Json::array();
  for (const auto &c : *calls) {
    RequestContext item{context.id, context.sender, c.value("operation", ""), c.value("target", ""),
                        context.received};
    const Json item_body = c.value("body", Json::object());
    results.push_back(reply_json(item.operation == kBatch
                                     ? call_error(Status::BadRequest, "batches do not nest")
                                     : dispatch(item, item_body)));
  }
  return Json{{"results", std::move(results)}};
}

void Endpoint::Impl::serve(RequestContext context, Json body) {
  CallResult<Json> result =
      body.is_discarded() ? call_error(Status::BadRequest, "the request body is not valid JSON")
      : context.operation == kBatch ? run_batch(context, body)
                                    : dispatch(context, body);
  const std::string reply_body = result ? result->dump() : std::string();
  const std::string error = result ? std::string() : result.error().message;
  rsca_ctl_Reply reply{};
  reply.id = const_cast<char *>(context.id.c_str());
  reply.status = static_cast<std::int32_t>(result ? Status::Ok : result.error().status);
  reply.error = const_cast<char *>(error.c_str());
  reply.body = const_cast<char *>(reply_body.c_str());
  auto writer =
      reply_ways->matched_writer(context.sender, Clock::now() + std::chrono::seconds(5), stopping);
  if (!writer) {
    spdlog::warn("{}: cannot reply to {} for {}: {}", address, context.sender, context.operation,
                 writer.error().message);
    return;
  }
  if (dds_return_t rc = dds_write(*writer, &reply); rc < 0)
    spdlog::warn("{}: reply to {} failed: {}", address, context.sender, dds_strretcode(rc));
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
      const auto status = static_cast<Status>(r->status);
      if (status != Status::Ok) {
        complete(str(r->id), call_error(status, str(r->error)));
        continue;
      }
      Json body = parse_body(r->body);
      complete(str(r->id),
               body.is_discarded()
                   ? CallResult<Json>(call_error(Status::Failed, "the reply is not JSON"))
                   : CallResult<Json>(std::move(body)));
    }
    dds_return_loan(reply_reader.get(), samples, n);
  }
}

void Endpoint::Impl::take_announcements() {
  void *samples[kTakeBatch] = {nullptr};
  dds_sample_info_t infos[kTakeBatch];
  for (;;) {
    const dds_return_t n =
        dds_take(announcement_reader.get(), samples, infos, kTakeBatch, kTakeBatch);
    if (n <= 0)
      return;
    const AnnouncementHandler &handler = options.on_announcement;
    for (dds_return_t i = 0; i < n; ++i) {
      const auto *a = static_cast<const rsca_ctl_Announcement *>(samples[i]);
      AnnouncementEvent event;
      event.address = str(a->address);
      if (infos[i].valid_data && infos[i].instance_state == DDS_IST_ALIVE) {
        event.kind = AnnouncementEvent::Kind::Alive;
        event.endpoint_kind = str(a->kind);
        event.body = parse_body(a->body);
      } else if (infos[i].instance_state != DDS_IST_ALIVE) {
        event.kind = AnnouncementEvent::Kind::Gone;
      } else {
        continue;
      }
      if (event.kind == AnnouncementEvent::Kind::Alive &&
          std::find(options.prepare_kinds.begin(), options.prepare_kinds.end(),
                    event.endpoint_kind) != options.prepare_kinds.end())
        request_ways->writer_for(event.address); // not waited for
      handler(event);
    }
    dds_return_loan(announcement_reader.get(), samples, n);
  }
}

void Endpoint::Impl::complete(const std::string &id, CallResult<Json> result) {
  std::unique_lock lock(state_mutex);
  auto it = pending.find(id);
  if (it == pending.end())
    return; // already timed out, or not ours
  auto promise = std::move(it->second.promise);
  pending.erase(it);
  lock.unlock();
  promise.set_value(std::move(result));
}

void Endpoint::Impl::fail_calls(
    const std::function<std::optional<CallError>(const Pending &)> &failure) {
  std::vector<std::pair<std::promise<CallResult<Json>>, CallError>> failed;
  {
    std::lock_guard lock(state_mutex);
    for (auto it = pending.begin(); it != pending.end();) {
      auto error = failure(it->second);
      if (!error) {
        ++it;
        continue;
      }
      failed.emplace_back(std::move(it->second.promise), std::move(*error));
      it = pending.erase(it);
    }
  }
  for (auto &[promise, error] : failed)
    promise.set_value(tl::unexpected(std::move(error)));
}

void Endpoint::Impl::expire_calls() {
  const auto now = Clock::now();
  fail_calls([now](const Pending &p) -> std::optional<CallError> {
    if (p.deadline > now)
      return std::nullopt;
    if (p.sent)
      return CallError{
          Status::Timeout,
          fmt::format("no reply from {} to \"{}\" before the deadline", p.target, p.operation)};
    return CallError{Status::Unavailable, fmt::format("nobody serves address {}", p.target)};
  });
}

// A call whose addressee left DDS after it was sent (its process exited, or lost its lease)
// fails now instead of at its deadline: a CLI whose domain daemon died during a launch says so
// within a lease, not after six times its timeout (issue 18, defect 10).
void Endpoint::Impl::fail_calls_to_departed() {
  const auto now = Clock::now();
  if (now - departures_checked < kDepartureCheck)
    return;
  departures_checked = now;
  {
    std::lock_guard lock(state_mutex);
    if (std::none_of(pending.begin(), pending.end(), [](const auto &p) { return p.second.sent; }))
      return;
  }
  const std::set<std::string> gone = request_ways->departed();
  if (gone.empty())
    return;
  std::map<std::string, std::string> via;
  {
    std::lock_guard lock(routes_mutex);
    via = routes;
  }
  fail_calls([&](const Pending &p) -> std::optional<CallError> {
    auto route = via.find(p.target);
    if (!p.sent || gone.count(route != via.end() ? route->second : p.target) == 0)
      return std::nullopt;
    return CallError{Status::Unavailable,
                     fmt::format("{} left before it replied to \"{}\": its endpoint is gone from "
                                 "DDS (the process exited or lost its lease)",
                                 p.target, p.operation),
                     /*maybe_received=*/true};
  });
}

void Endpoint::Impl::send_request(std::string id, std::string target, std::string operation,
                                  std::string body) {
  Clock::time_point deadline;
  {
    std::lock_guard lock(state_mutex);
    auto it = pending.find(id);
    if (it == pending.end())
      return; // expired before it could be sent
    deadline = it->second.deadline;
  }
  auto writer = request_ways->matched_writer(route_of(target), deadline, stopping);
  if (!writer) {
    complete(id, tl::unexpected(writer.error()));
    return;
  }
  {
    // The addressee is matched: from here silence is a timeout, also when the deadline passes
    // during the write, and never "nobody serves" for a request it may well have received.
    std::lock_guard lock(state_mutex);
    auto it = pending.find(id);
    if (it == pending.end())
      return; // expired while its addressee was awaited
    it->second.sent = true;
  }
  rsca_ctl_Request request{};
  request.id = id.data();
  request.sender = address.data();
  request.target = target.data();
  request.operation = operation.data();
  request.body = body.data();
  if (dds_return_t rc = dds_write(*writer, &request); rc < 0) {
    complete(id, call_error(Status::Failed,
                            fmt::format("sending to {} failed: {}", target, dds_strretcode(rc))));
    return;
  }
}

std::string Endpoint::Impl::route_of(const std::string &target) {
  std::lock_guard lock(routes_mutex);
  auto it = routes.find(target);
  return it != routes.end() ? it->second : target;
}

Expected<void> Endpoint::Impl::announce(const std::string &as, const std::string &kind,
                                        const Json &body) {
  std::lock_guard lock(announcement_mutex);
  if (!announcement_writer) {
    auto qos = announcement_qos();
    auto w = dds::checked(
        dds_create_writer(participant->get(), announcement_topic.get(), qos.get(), nullptr),
        "creating the announcement writer");
    if (!w)
      return tl::unexpected(w.error());
    announcement_writer = std::move(*w);
  }
  const std::string text = body.dump();
  rsca_ctl_Announcement a{};
  a.address = const_cast<char *>(as.c_str());
  a.kind = const_cast<char *>(kind.c_str());
  a.body = const_cast<char *>(text.c_str());
  if (dds_return_t rc = dds_write(announcement_writer.get(), &a); rc < 0)
    return tl::unexpected(dds::dds_error(rc, "announcing"));
  return {};
}

void Endpoint::Impl::withdraw(const std::string &as) {
  std::lock_guard lock(announcement_mutex);
  if (!announcement_writer)
    return;
  rsca_ctl_Announcement a{};
  a.address = const_cast<char *>(as.c_str());
  a.kind = const_cast<char *>("");
  a.body = const_cast<char *>("");
  dds_dispose(announcement_writer.get(), &a);
}

Endpoint::Endpoint(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Expected<std::unique_ptr<Endpoint>> Endpoint::open(std::shared_ptr<dds::Participant> participant,
                                                   std::string address, EndpointOptions options) {
  auto invalid = [](const std::string &a) {
    return a.empty() || a.find_first_of("*?[]\\") != std::string::npos;
  };
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
  std::lock_guard lock(impl_->state_mutex);
  impl_->handlers[{std::string(), operation}] = std::move(handler);
}

void Endpoint::on(const std::string &address, const std::string &operation, Handler handler) {
  std::lock_guard lock(impl_->state_mutex);
  impl_->handlers[{address, operation}] = std::move(handler);
}

void Endpoint::start_serving() {
  dds_set_status_mask(impl_->request_reader.get(), DDS_DATA_AVAILABLE_STATUS);
  impl_->serving = true;
  impl_->wake(); // takes what was held
}

void Endpoint::stop_serving(const std::string &address) {
  std::unique_lock lock(impl_->state_mutex);
  std::erase_if(impl_->handlers, [&](const auto &entry) { return entry.first.first == address; });
  impl_->handler_done.wait(lock, [&] { return !impl_->running.contains(address); });
}

std::vector<CallResult<Json>> Endpoint::call_all(const std::vector<Call> &calls,
                                                 std::chrono::milliseconds timeout) {
  // Calls to the addresses one endpoint serves, by that endpoint: two and more go as a batch.
  std::map<std::string, std::vector<std::size_t>> by_endpoint;
  for (std::size_t i = 0; i < calls.size(); ++i)
    by_endpoint[impl_->route_of(calls[i].target)].push_back(i);
  std::vector<std::future<CallResult<Json>>> single(calls.size());
  std::vector<std::pair<std::vector<std::size_t>, std::future<CallResult<Json>>>> batches;
  for (auto &[via, indexes] : by_endpoint) {
    const bool routed = via != calls[indexes.front()].target;
    if (!routed || indexes.size() < 2) {
      for (auto i : indexes)
        single[i] = call(calls[i].target, calls[i].operation, calls[i].body, timeout);
      continue;
    }
    Json items = Json::array();
    for (auto i : indexes)
      items.push_back({{"target", calls[i].target},
                       {"operation", calls[i].operation},
                       {"body", calls[i].body}});
    batches.emplace_back(indexes, call(via, kBatch, Json{{"calls", std::move(items)}}, timeout));
  }
  std::vector<CallResult<Json>> results(calls.size(), call_error(Status::Failed, "not made"));
  for (auto &[indexes, future] : batches) {
    auto reply = future.get();
    const Json none = Json::array();
    const Json &items = reply ? reply->value("results", none) : none;
    for (std::size_t k = 0; k < indexes.size(); ++k)
      results[indexes[k]] = !reply ? CallResult<Json>(tl::unexpected(reply.error()))
                            : k < items.size()
                                ? result_of(items[k])
                                : call_error(Status::Failed, "the batch reply is short");
  }
  for (std::size_t i = 0; i < calls.size(); ++i)
    if (single[i].valid())
      results[i] = single[i].get();
  return results;
}

void Endpoint::route(const std::string &target, const std::string &via) {
  std::lock_guard lock(impl_->routes_mutex);
  impl_->routes[target] = via;
}

std::future<CallResult<Json>> Endpoint::call(const std::string &target,
                                             const std::string &operation, Json body,
                                             std::chrono::milliseconds timeout) {
  std::future<CallResult<Json>> future;
  std::string id;
  {
    std::lock_guard lock(impl_->state_mutex);
    id = fmt::format("{}#{}", impl_->address, ++impl_->next_id);
    Impl::Pending pending{{}, Clock::now() + timeout, target, operation};
    future = pending.promise.get_future();
    impl_->pending.emplace(id, std::move(pending));
  }
  impl_->wake(); // the receiver recomputes its timeout
  impl_->send_pool->post([impl = impl_.get(), id, target, operation, text = body.dump()]() mutable {
    impl->send_request(std::move(id), std::move(target), std::move(operation), std::move(text));
  });
  return future;
}

void Endpoint::prepare(const std::string &target) {
  if (auto writer = impl_->request_ways->writer_for(impl_->route_of(target)); !writer)
    spdlog::debug("preparing the way to {}: {}", target, writer.error().message);
}

void Endpoint::prepare_replies(const std::string &caller) {
  if (auto writer = impl_->reply_ways->writer_for(caller); !writer)
    spdlog::debug("preparing replies to {}: {}", caller, writer.error().message);
}

void Endpoint::abandon(const std::string &target, const std::string &why) {
  impl_->fail_calls([&](const Impl::Pending &p) -> std::optional<CallError> {
    if (p.target != target)
      return std::nullopt;
    return CallError{Status::Unavailable,
                     fmt::format("{} to \"{}\": {}", p.target, p.operation, why)};
  });
}

void Endpoint::forget(const std::string &target) {
  impl_->request_ways->erase(target);
  impl_->reply_ways->erase(target);
  std::lock_guard lock(impl_->routes_mutex);
  impl_->routes.erase(target);
}

Expected<void> Endpoint::announce(const std::string &kind, const Json &body) {
  return impl_->announce(impl_->address, kind, body);
}

void Endpoint::withdraw() {
  impl_->withdraw(impl_->address);
}

Expected<void> Endpoint::announce(const std::string &alias, const std::string &kind,
                                  const Json &body) {
  return impl_->announce(alias, kind, body);
}

void Endpoint::withdraw(const std::string &alias) {
  impl_->withdraw(alias);
}

} // namespace rsca::control
