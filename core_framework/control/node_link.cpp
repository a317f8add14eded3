#include "control/node_link.hpp"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <thread>

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/eventfd.h>

#include "control/handler_table.hpp"
#include "control/link_socket.hpp"
#include "control/worker_pool.hpp"

namespace rsca::control {

namespace link = protocol::link;
using Clock = std::chrono::steady_clock;

struct NodeLink::Impl {
  process::Fd fd;
  process::Fd wake; // an eventfd: ends the reader's poll
  std::string address;
  std::unique_ptr<LinkWriter> writer;
  std::unique_ptr<WorkerPool> handler_pool;
  std::thread reader;
  std::atomic<bool> stopping{false};

  HandlerTable served;

  std::mutex mutex; // guards what follows
  struct Pending {
    std::promise<CallResult<Json>> promise;
    Clock::time_point deadline;
  };
  std::map<std::string, Pending> pending;
  std::uint64_t next_id = 0;
  bool closed = false; // the node closed the link: calls fail at once

  void read_loop();
  void take(link::Frame frame);
  void serve(link::Request request);
  void complete(const std::string &id, CallResult<Json> result);
  void fail_all(const std::string &why);
  void expire();
  int poll_timeout_ms();
};

void NodeLink::Impl::read_loop() {
  FrameReader frames_in;
  std::vector<link::Frame> frames;
  std::string why;
  while (!stopping) {
    pollfd fds[2] = {{fd.get(), POLLIN, 0}, {wake.get(), POLLIN, 0}};
    if (::poll(fds, 2, poll_timeout_ms()) < 0 && errno != EINTR)
      break;
    if ((fds[1].revents & POLLIN) != 0) {
      // Drained, or it stays readable and every later poll returns at once: the reader would
      // spin on a CPU for as long as the link lives.
      std::uint64_t count = 0;
      [[maybe_unused]] auto n = ::read(wake.get(), &count, sizeof(count));
    }
    expire();
    if (stopping || (fds[0].revents & (POLLIN | POLLHUP | POLLERR)) == 0)
      continue;
    frames.clear();
    const bool open = frames_in.read_from(fd.get(), frames, why);
    for (const auto &answer : frames_in.answers())
      (void)writer->send(answer);
    for (auto &f : frames)
      take(std::move(f));
    if (!open) {
      if (!stopping)
        spdlog::error("{}: the link to the node ended: {}", address, why);
      fail_all("the link to the node ended: " + why);
      return;
    }
  }
}

void NodeLink::Impl::take(link::Frame frame) {
  if (auto *request = std::get_if<link::Request>(&frame)) {
    handler_pool->post([this, r = std::move(*request)]() mutable { serve(std::move(r)); });
    return;
  }
  if (auto *reply = std::get_if<link::Reply>(&frame)) {
    complete(reply->id, reply_result(*reply));
    return;
  }
  spdlog::warn("{}: the node sent a frame a process does not take", address);
}

void NodeLink::Impl::serve(link::Request request) {
  RequestContext context{request.id, request.sender, request.operation, request.target,
                         Clock::now()};
  if (context.target.empty())
    context.target = address;
  const auto result = served.dispatch(context, request.body);
  if (auto sent = writer->send(link_reply(request.id, result)); !sent)
    spdlog::warn("{}: reply to {} for {} failed: {}", address, request.sender, request.operation,
                 sent.error());
}

void NodeLink::Impl::complete(const std::string &id, CallResult<Json> result) {
  std::lock_guard lock(mutex);
  auto it = pending.find(id);
  if (it == pending.end())
    return; // expired already
  it->second.promise.set_value(std::move(result));
  pending.erase(it);
}

void NodeLink::Impl::fail_all(const std::string &why) {
  std::lock_guard lock(mutex);
  closed = true;
  // Each was sent to the node, which may have made it: the caller cannot know its outcome.
  for (auto &[id, p] : pending)
    p.promise.set_value(
        tl::unexpected(CallError{Status::Unavailable, why, /*maybe_received=*/true}));
  pending.clear();
}

void NodeLink::Impl::expire() {
  const auto now = Clock::now();
  std::lock_guard lock(mutex);
  for (auto it = pending.begin(); it != pending.end();) {
    if (it->second.deadline > now) {
      ++it;
      continue;
    }
    it->second.promise.set_value(call_error(Status::Timeout, "no reply in time"));
    it = pending.erase(it);
  }
}

int NodeLink::Impl::poll_timeout_ms() {
  constexpr int kIdle = 1000;
  std::lock_guard lock(mutex);
  auto next = Clock::now() + std::chrono::milliseconds(kIdle);
  for (const auto &[id, p] : pending)
    next = std::min(next, p.deadline);
  const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(next - Clock::now());
  return static_cast<int>(std::clamp<std::int64_t>(wait.count() + 1, 0, kIdle));
}

std::optional<process::Fd> NodeLink::inherited() {
  const char *text = std::getenv(link::kNodeLinkVariable);
  if (text == nullptr)
    return std::nullopt;
  int fd = -1;
  const std::string_view value(text);
  const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), fd);
  ::unsetenv(link::kNodeLinkVariable);
  if (error != std::errc() || end != value.data() + value.size() || fd < 0) {
    spdlog::warn("{}=\"{}\" is not a descriptor: not using a node link", link::kNodeLinkVariable,
                 value);
    return std::nullopt;
  }
  ::fcntl(fd, F_SETFD, FD_CLOEXEC); // not passed on to what this process starts
  return process::Fd(fd);
}

Expected<std::unique_ptr<NodeLink>> NodeLink::open(process::Fd link, std::string address,
                                                   std::size_t workers) {
  auto impl = std::make_unique<Impl>();
  impl->wake = process::Fd(::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK));
  if (!impl->wake)
    return make_error({"control", 0, 0}, "node-link",
                      fmt::format("eventfd: {}", std::strerror(errno)));
  impl->fd = std::move(link);
  impl->address = std::move(address);
  impl->writer = std::make_unique<LinkWriter>(impl->fd.get());
  impl->handler_pool = std::make_unique<WorkerPool>(std::max<std::size_t>(1, workers));
  Impl *raw = impl.get();
  impl->reader = std::thread([raw] { raw->read_loop(); });
  return std::unique_ptr<NodeLink>(new NodeLink(std::move(impl)));
}

NodeLink::NodeLink(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

NodeLink::~NodeLink() {
  // The handlers under way first: their replies still go out over the link.
  impl_->handler_pool->stop();
  impl_->stopping = true;
  const std::uint64_t one = 1;
  [[maybe_unused]] auto n = ::write(impl_->wake.get(), &one, sizeof(one));
  impl_->reader.join();
  impl_->fail_all("the link is closing");
}

const std::string &NodeLink::address() const {
  return impl_->address;
}

void NodeLink::on(const std::string &operation, Handler handler) {
  impl_->served.on(std::string(), operation, std::move(handler));
}

void NodeLink::on(const std::string &address, const std::string &operation, Handler handler) {
  impl_->served.on(address, operation, std::move(handler));
}

void NodeLink::stop_serving(const std::string &address) {
  impl_->served.drop(address);
}

std::future<CallResult<Json>> NodeLink::call(const std::string &target,
                                             const std::string &operation, Json body,
                                             std::chrono::milliseconds timeout) {
  std::promise<CallResult<Json>> promise;
  auto future = promise.get_future();
  std::string id;
  {
    std::lock_guard lock(impl_->mutex);
    if (impl_->closed) {
      promise.set_value(call_error(Status::Unavailable, "the link to the node has ended"));
      return future;
    }
    id = std::to_string(++impl_->next_id);
    impl_->pending[id] = {std::move(promise), Clock::now() + timeout};
  }
  link::Request request{id, target, operation, impl_->address, timeout.count(), std::move(body)};
  if (auto sent = impl_->writer->send(request); !sent)
    impl_->complete(id, call_error(Status::Unavailable, sent.error()));
  const std::uint64_t one = 1; // the reader's poll learns the new deadline
  [[maybe_unused]] auto n = ::write(impl_->wake.get(), &one, sizeof(one));
  return future;
}

std::vector<CallResult<Json>> NodeLink::call_all(const std::vector<Call> &calls,
                                                 std::chrono::milliseconds timeout) {
  std::vector<std::future<CallResult<Json>>> futures;
  futures.reserve(calls.size());
  for (const auto &c : calls)
    futures.push_back(call(c.target, c.operation, c.body, timeout));
  std::vector<CallResult<Json>> results;
  results.reserve(calls.size());
  for (auto &f : futures)
    results.push_back(f.get());
  return results;
}

void NodeLink::route(const std::string &target, const std::string &via) {
  if (auto sent = impl_->writer->send(link::Route{target, via}); !sent)
    spdlog::warn("{}: routing {} via {}: {}", impl_->address, target, via, sent.error());
}

Expected<void> NodeLink::announce(const std::string &address, const std::string &kind,
                                  const Json &body) {
  if (auto sent = impl_->writer->send(link::Announce{address, kind, body}); !sent)
    return make_error({"control", 0, 0}, "node-link",
                      fmt::format("announcing {}: {}", address, sent.error()));
  return {};
}

void NodeLink::withdraw(const std::string &address) {
  if (auto sent = impl_->writer->send(link::Withdraw{address}); !sent)
    spdlog::warn("{}: withdrawing {}: {}", impl_->address, address, sent.error());
}

} // namespace rsca::control
