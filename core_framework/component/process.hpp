// Private to the component runtime: what a process that serves components needs around them (a
// component process, a component host): exit events, its logger, and dying with its node.
#pragma once

#include <sys/eventfd.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <poll.h>
#include <pthread.h>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>
#include <tl/expected.hpp>

#include "component/runtime.hpp"
#include "profile/profile_loader.hpp"

namespace rsca::component::detail {

// ---------------------------------------------------------------------------------------------
// Exit events: SIGINT/SIGTERM through a signalfd (the signals are blocked in every thread, so no
// handler runs), and component.release through an eventfd.

class UniqueFd {
public:
  explicit UniqueFd(int fd = -1) : fd_(fd) {}
  ~UniqueFd() {
    if (fd_ >= 0)
      ::close(fd_);
  }
  UniqueFd(UniqueFd &&other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  UniqueFd &operator=(UniqueFd &&) = delete;
  UniqueFd(const UniqueFd &) = delete;
  UniqueFd &operator=(const UniqueFd &) = delete;
  int get() const { return fd_; }

private:
  int fd_;
};

class ExitEvents {
public:
  enum class Event : std::uint8_t { None, Signal, Released };

  // Blocks SIGINT and SIGTERM in the calling thread and so in every thread it starts later.
  static tl::expected<ExitEvents, std::string> install() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    if (int rc = pthread_sigmask(SIG_BLOCK, &set, nullptr); rc != 0)
      return tl::unexpected(fmt::format("blocking signals: {}", std::strerror(rc)));
    UniqueFd signals(signalfd(-1, &set, SFD_CLOEXEC | SFD_NONBLOCK));
    if (signals.get() < 0)
      return tl::unexpected(fmt::format("signalfd: {}", std::strerror(errno)));
    UniqueFd released(eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK));
    if (released.get() < 0)
      return tl::unexpected(fmt::format("eventfd: {}", std::strerror(errno)));
    return ExitEvents(std::move(signals), std::move(released));
  }

  void notify_released() const {
    const std::uint64_t one = 1;
    [[maybe_unused]] auto n = ::write(released_.get(), &one, sizeof one);
  }

  // Waits at most `timeout` for a signal or a release; `signal` is set for a signal.
  Event wait(std::chrono::milliseconds timeout, int &signal) const {
    pollfd fds[2] = {{signals_.get(), POLLIN, 0}, {released_.get(), POLLIN, 0}};
    if (::poll(fds, 2, static_cast<int>(timeout.count())) <= 0)
      return Event::None;
    if ((fds[0].revents & POLLIN) != 0) {
      signalfd_siginfo info{};
      if (::read(signals_.get(), &info, sizeof info) == static_cast<ssize_t>(sizeof info)) {
        signal = static_cast<int>(info.ssi_signo);
        return Event::Signal;
      }
    }
    if ((fds[1].revents & POLLIN) != 0)
      return Event::Released;
    return Event::None;
  }

private:
  ExitEvents(UniqueFd signals, UniqueFd released)
      : signals_(std::move(signals)), released_(std::move(released)) {}
  UniqueFd signals_;
  UniqueFd released_;
};

inline std::shared_ptr<spdlog::logger> make_logger(const std::string &name) {
  auto logger =
      std::make_shared<spdlog::logger>(name, std::make_shared<spdlog::sinks::stderr_sink_mt>());
  logger->flush_on(spdlog::level::warn);
  spdlog::set_default_logger(logger); // the framework's own messages carry the instance name too
  return logger;
}

// A component does not outlive the node daemon that started it. With the node gone nobody could
// escalate a stuck shutdown, so its death kills the process outright; the domain learns of it
// from the node's loss. The node may die before this runs, its orphan adopted by another
// process: the node's pid in the environment tells them apart. False: the node is already gone.
bool die_with_node();

// The profiles of a process's components, in the order of `spds`, read with one loader: each SPD
// once, from its runtime model where the domain wrote one, else from its XML (said at debug
// level). The loader goes on return: an XML reader it needed is unloaded before any component
// runs. An error names the profile that cannot be read.
tl::expected<std::vector<std::shared_ptr<const profile::ResolvedSoftPkg>>, std::string>
load_component_profiles(const std::vector<std::string> &spds, spdlog::logger &log);

// Waits for a signal or `released`; true for a signal (`signal` says which).
bool wait_for_signal_or_release(const ExitEvents &events, int &signal);

// The life of a process that serves components (a component process, a component host): it dies
// with its node, blocks the exit signals before any thread starts, parses its exec parameters
// (`usage` says what they are when they are wrong), names its logger, and returns what `serve`
// returns. The exit statuses are component/runtime.hpp's.
template <typename Params>
int run_process(
    int argc, char **argv, std::string_view usage,
    const std::function<tl::expected<Params, std::string>(int, const char *const *)> &parse,
    const std::function<std::string(const Params &)> &logger_name,
    const std::function<int(const Params &, const ExitEvents &, std::shared_ptr<spdlog::logger>)>
        &serve) {
  if (!die_with_node())
    return kExitFailure;
  auto events = ExitEvents::install();
  if (!events) {
    spdlog::error("{}", events.error());
    return kExitFailure;
  }
  auto params = parse(argc, argv);
  if (!params) {
    spdlog::error("{}\nusage: {} {}", params.error(), argc > 0 ? argv[0] : "component", usage);
    return kExitUsage;
  }
  auto logger = make_logger(logger_name(*params));
  try {
    return serve(*params, *events, logger);
  } catch (const std::exception &e) {
    logger->critical("{}", e.what());
    return kExitFailure;
  }
}

} // namespace rsca::component::detail
