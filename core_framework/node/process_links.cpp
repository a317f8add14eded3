#include "node/process_links.hpp"
#include "node/process_links_impl.hpp"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <functional>
#include <future>
#include <map>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include "control/link_socket.hpp"
#include "control/worker_pool.hpp"
#include "protocol/addresses.hpp"
#include "protocol/component_ops.hpp"

namespace rsca::node {

namespace {

std::future<CallResult<Json>> ready(CallResult<Json> result) {
  std::promise<CallResult<Json>> promise;
  promise.set_value(std::move(result));
  return promise.get_future();
}

} // namespace

std::future<CallResult<Json>> ProcessLinks::Impl::relay(const Json &body,
                                                        const control::RequestContext &context) {
  std::shared_ptr<LinkedProcess> process;
  std::string id;
  std::future<CallResult<Json>> reply;
  {
    std::lock_guard lock(mutex);
    auto it = by_address.find(context.target);
    if (closed || it == by_address.end())
      return ready(
          call_error(Status::Unavailable, fmt::format("{} is not served here", context.target)));
    process = it->second;
    if (process->ended)
      return ready(call_error(Status::Unavailable,
                              fmt::format("pid {} has exited: {}", process->pid, process->why)));
  }
  std::function<void(bool ok)> after;
  auto prepared = prepare(process->pid, body, context, after);
  if (!prepared)
    return ready(tl::unexpected(prepared.error()));
  {
    std::lock_guard lock(mutex);
    id = std::to_string(++next_id);
    auto &r = relayed[id];
    r.pid = process->pid;
    r.deadline = std::chrono::steady_clock::now() + kRelayBound;
    r.after = std::move(after);
    reply = r.promise.get_future();
  }
  const link::Request request{id,
                              context.target,
                              context.operation,
                              context.sender,
                              std::chrono::milliseconds(kRelayBound).count(),
                              std::move(*prepared)};
  if (auto sent = process->writer->send(request); !sent) {
    complete(
        id, process->pid,
        call_error(Status::Unavailable, fmt::format("pid {}: {}", process->pid, sent.error())));
  }
  return reply;
}

CallResult<Json> ProcessLinks::Impl::prepare(pid_t pid, const Json &body,
                                             const control::RequestContext &context,
                                             std::function<void(bool ok)> &after) {
  namespace op = protocol::component;
  if (host_data == nullptr)
    return body;
  // An end goes once the process has let go of it: the one a connect replaced, a new one the
  // process refused, a disconnected one. A request that does not decode is handed on as it is:
  // the process says what is wrong with it.
  if (context.operation == op::Disconnect::name) {
    if (auto r = protocol::decode<op::DisconnectRequest>(body))
      after = [data = host_data, pid, target = context.target, r = *r](bool) {
        data->disconnect(pid, target, r.port, r.connection);
      };
    return body;
  }
  if (context.operation != op::Connect::name)
    return body;
  auto r = protocol::decode<op::ConnectRequest>(body);
  if (!r)
    return body;
  after = [data = host_data, pid, target = context.target, port = r->port,
           connection = r->connection](bool ok) {
    data->connected(pid, target, port, connection, ok);
  };
  if (!r->shared_memory.value_or(false))
    return body;
  auto ring = host_data->connect(pid, context.target, *r);
  if (!ring)
    return call_error(Status::Failed, fmt::format("{}: {}", context.target, ring.error()));
  r->ring = *ring;
  return protocol::encode_message(*r);
}

void ProcessLinks::Impl::complete(const std::string &id, pid_t pid, CallResult<Json> result) {
  std::function<void(bool ok)> after;
  const bool ok = result.has_value();
  {
    std::lock_guard lock(mutex);
    auto it = relayed.find(id);
    // Only the process asked may answer: a reply to another's request is dropped.
    if (it == relayed.end() || it->second.pid != pid)
      return;
    after = std::move(it->second.after);
    it->second.promise.set_value(std::move(result));
    relayed.erase(it);
  }
  if (after)
    after(ok);
}

// Relayed requests past their bound fail (the process lives but does not answer).
void ProcessLinks::Impl::expire() {
  const auto now = std::chrono::steady_clock::now();
  std::vector<std::function<void(bool)>> afters;
  {
    std::lock_guard lock(mutex);
    for (auto it = relayed.begin(); it != relayed.end();) {
      if (it->second.deadline > now) {
        ++it;
        continue;
      }
      it->second.promise.set_value(
          call_error(Status::Timeout, fmt::format("pid {} did not answer in {} s", it->second.pid,
                                                  kRelayBound.count())));
      if (it->second.after)
        afters.push_back(std::move(it->second.after));
      it = relayed.erase(it);
    }
  }
  for (auto &after : afters)
    after(false);
}

void ProcessLinks::Impl::poll_loop() {
  constexpr int kEvents = 64;
  epoll_event events[kEvents];
  while (!stopping) {
    const int n = ::epoll_wait(epoll.get(), events, kEvents, 1000);
    expire();
    resume_accepting();
    drop_idle_clients();
    if (n < 0 && errno != EINTR) {
      spdlog::error("process links: epoll_wait: {}", std::strerror(errno));
      return;
    }
    for (int i = 0; i < n && !stopping; ++i) {
      const int fd = events[i].data.fd;
      if (fd == listener_fd.load())
        accept_clients();
      else if (fd != wake.get())
        read(fd);
    }
  }
}

void ProcessLinks::Impl::read(int fd) {
  std::shared_ptr<LinkedProcess> process;
  {
    std::lock_guard lock(mutex);
    auto it = by_fd.find(fd);
    if (it == by_fd.end())
      return;
    process = it->second;
  }
  std::vector<link::Frame> frames;
  std::string why;
  const bool open = process->reader.read_from(fd, frames, why);
  if (!frames.empty())
    process->heard = std::chrono::steady_clock::now();
  for (const auto &answer : process->reader.answers())
    (void)process->writer->send(answer);
  for (auto &f : frames)
    take(process, std::move(f));
  if (open)
    return;
  std::lock_guard lock(mutex);
  ::epoll_ctl(epoll.get(), EPOLL_CTL_DEL, fd, nullptr);
  by_fd.erase(fd);
  if (process->client)
    --clients;
  end(*process, why);
}

void ProcessLinks::Impl::take(const std::shared_ptr<LinkedProcess> &process, link::Frame frame) {
  if (process->client && !std::holds_alternative<link::Request>(frame)) {
    spdlog::warn("control socket: client pid {} sent a frame other than a request: ignored",
                 process->pid);
    return;
  }
  if (auto *reply = std::get_if<link::Reply>(&frame)) {
    complete(reply->id, process->pid, control::reply_result(*reply));
  } else if (auto *request = std::get_if<link::Request>(&frame)) {
    if (request->target == link::kHelloTarget && request->operation == link::kHelloOperation) {
      (void)process->writer->send(
          control::link_reply(request->id, Json{{"node", endpoint->address()}}));
      return;
    }
    if (!process->client) {
      outgoing->post(
          [this, process, r = std::move(*request)]() mutable { make_call(process, std::move(r)); });
      return;
    }
    if (process->calls.fetch_add(1) >= kMaxClientCalls) {
      process->calls.fetch_sub(1);
      (void)process->writer->send(control::link_reply(
          request->id, call_error(Status::Rejected, fmt::format("over {} calls under way at once",
                                                                kMaxClientCalls))));
      return;
    }
    client_calls->post([this, process, r = std::move(*request)]() mutable {
      make_call(process, std::move(r));
      process->heard = std::chrono::steady_clock::now(); // before the count: never idle between
      process->calls.fetch_sub(1);
    });
  } else if (auto *a = std::get_if<link::Announce>(&frame)) {
    announce(*process, *a);
  } else if (auto *w = std::get_if<link::Withdraw>(&frame)) {
    std::lock_guard lock(mutex);
    if (process->announced.erase(w->address) != 0)
      endpoint->withdraw(w->address);
  } else if (auto *r = std::get_if<link::Route>(&frame)) {
    // A process may say where a component is served, nothing else: the domain's and the nodes'
    // ways stay the node's own.
    if (!protocol::incarnation_of(r->target)) {
      spdlog::warn("pid {} asked to route {}, which is no component's address: ignored",
                   process->pid, r->target);
      return;
    }
    endpoint->route(r->target, r->via);
  }
}

void ProcessLinks::Impl::make_call(const std::shared_ptr<LinkedProcess> &process,
                                   link::Request request) {
  const auto bound = process->client ? std::chrono::milliseconds(kClientCallBound)
                                     : std::chrono::milliseconds(kCallBound);
  const auto timeout = std::clamp(std::chrono::milliseconds(request.timeout_ms),
                                  std::chrono::milliseconds(1), bound);
  auto result = endpoint->call(request.target, request.operation, std::move(request.body), timeout);
  // Polled, so that closing the node, or the caller going, does not wait for a call's whole
  // timeout (the call itself ends at its deadline in the endpoint).
  while (result.wait_for(std::chrono::milliseconds(100)) != std::future_status::ready)
    if (stopping || process->ended)
      return;
  const auto reply = control::link_reply(request.id, result.get());
  if (auto sent = process->writer->send(reply); !sent)
    spdlog::debug("pid {}: the reply to its {} is lost: {}", process->pid, request.operation,
                  sent.error());
}

void ProcessLinks::Impl::announce(LinkedProcess &process, const link::Announce &a) {
  std::lock_guard lock(mutex);
  if (std::find(process.addresses.begin(), process.addresses.end(), a.address) ==
      process.addresses.end()) {
    spdlog::warn("pid {} announced {}, which it was not started to serve: ignored", process.pid,
                 a.address);
    return;
  }
  if (process.ended)
    return;
  Json body = a.body;
  if (body.is_object())
    body[control::kAnnouncedVia] = endpoint->address();
  if (auto ok = endpoint->announce(a.address, a.kind, body); !ok) {
    spdlog::warn("announcing {} for pid {}: {}", a.address, process.pid, ok.error().to_string());
    return;
  }
  process.announced.insert(a.address);
}

void ProcessLinks::Impl::end(LinkedProcess &process, const std::string &why) {
  if (process.ended)
    return;
  process.ended = true;
  process.why = why;
  spdlog::debug("pid {}: its link ended: {}", process.pid, why);
  for (auto it = relayed.begin(); it != relayed.end();) {
    if (it->second.pid != process.pid) {
      ++it;
      continue;
    }
    it->second.promise.set_value(
        call_error(Status::Unavailable, fmt::format("pid {} has exited: {}", process.pid, why)));
    it = relayed.erase(it);
  }
  for (const auto &address : process.announced)
    endpoint->withdraw(address);
  process.announced.clear();
  // The descriptor stays open until the last reference to the process goes: a relay or a call
  // of the process still under way writes to it by number, and a number closed here could be
  // reused by the next process's link, which would then receive another's frames.
}

ProcessLinks::ProcessLinks(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Expected<std::unique_ptr<ProcessLinks>> ProcessLinks::start(control::Endpoint &endpoint,
                                                            HostData *host_data) {
  auto impl = std::make_unique<Impl>();
  impl->endpoint = &endpoint;
  impl->host_data = host_data;
  impl->epoll = process::Fd(::epoll_create1(EPOLL_CLOEXEC));
  impl->wake = process::Fd(::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK));
  if (!impl->epoll || !impl->wake)
    return make_error({"node", 0, 0}, "process-links",
                      fmt::format("epoll or eventfd: {}", std::strerror(errno)));
  epoll_event event{};
  event.events = EPOLLIN;
  event.data.fd = impl->wake.get();
  ::epoll_ctl(impl->epoll.get(), EPOLL_CTL_ADD, impl->wake.get(), &event);
  impl->outgoing = std::make_unique<control::WorkerPool>(4);
  impl->client_calls = std::make_unique<control::WorkerPool>(kClientCallThreads);
  Impl *raw = impl.get();
  impl->thread = std::thread([raw] { raw->poll_loop(); });
  return std::unique_ptr<ProcessLinks>(new ProcessLinks(std::move(impl)));
}

ProcessLinks::~ProcessLinks() {
  close();
}

void ProcessLinks::attach(pid_t pid, process::Fd link, std::vector<std::string> addresses) {
  auto process = std::make_shared<LinkedProcess>();
  process->pid = pid;
  process->addresses = std::move(addresses);
  process->writer = std::make_unique<control::LinkWriter>(link.get());
  const int fd = link.get();
  process->fd = std::move(link);
  {
    std::lock_guard lock(impl_->mutex);
    if (impl_->closed)
      return;
    impl_->by_pid[pid] = process;
    impl_->by_fd[fd] = process;
    for (const auto &a : process->addresses)
      impl_->by_address[a] = process;
  }
  Impl *raw = impl_.get();
  for (const auto &a : process->addresses)
    impl_->endpoint->relay(a, [raw](const Json &body, const control::RequestContext &context) {
      return raw->relay(body, context);
    });
  epoll_event event{};
  event.events = EPOLLIN;
  event.data.fd = fd;
  ::epoll_ctl(impl_->epoll.get(), EPOLL_CTL_ADD, fd, &event);
}

void ProcessLinks::detach(pid_t pid) {
  // Whatever the host's data holds for the process goes, also when it died before it was
  // attached.
  if (impl_->host_data != nullptr)
    impl_->host_data->forget(pid);
  std::shared_ptr<LinkedProcess> process;
  {
    std::lock_guard lock(impl_->mutex);
    if (impl_->closed)
      return;
    auto it = impl_->by_pid.find(pid);
    if (it == impl_->by_pid.end())
      return;
    process = it->second;
    impl_->by_pid.erase(it);
    if (process->fd) {
      ::epoll_ctl(impl_->epoll.get(), EPOLL_CTL_DEL, process->fd.get(), nullptr);
      impl_->by_fd.erase(process->fd.get());
    }
    for (const auto &a : process->addresses)
      impl_->by_address.erase(a);
    impl_->end(*process, "the process has exited");
  }
  // Not waited for: detach runs on the GPP's reaper thread, which a handler of the same batch
  // (a node.terminate) may be waiting on; the relays under way have failed already.
  for (const auto &a : process->addresses)
    impl_->endpoint->stop_relaying(a);
}

void ProcessLinks::close() {
  {
    std::lock_guard lock(impl_->mutex);
    if (impl_->closed)
      return;
    impl_->closed = true;
    for (auto &[pid, process] : impl_->by_pid)
      impl_->end(*process, "the node is stopping");
  }
  impl_->stopping = true;
  const std::uint64_t one = 1;
  [[maybe_unused]] auto n = ::write(impl_->wake.get(), &one, sizeof(one));
  impl_->thread.join();
  impl_->outgoing->stop();
  impl_->client_calls->stop();
  if (impl_->listener) {
    impl_->listener.reset();
    ::unlink(impl_->listener_path.c_str());
  }
}

} // namespace rsca::node
