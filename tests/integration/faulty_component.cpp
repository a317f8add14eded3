// rsca-test-faulty: a component that fails on purpose, as its "fault" exec parameter says, so
// that integration tests can see the domain roll a launch back. Test-only; never installed.
#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "component/runtime.hpp"
#include "control/link_socket.hpp"
#include "protocol/node_link.hpp"

namespace {

using rsca::component::Component;
using rsca::component::Context;
using rsca::component::Result;

// The fault is read from the command line before the runtime starts, because "never_register"
// must act before the component could announce itself.
std::string param_from(int argc, char **argv, const char *key, const char *otherwise) {
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], key) == 0)
      return argv[i + 1];
  return otherwise;
}

std::string g_fault = "none";
// "mark_signals": the file it creates once its handlers are in place (<marker>.ready), and on
// the first SIGINT or SIGTERM (<marker>); then it dies of it, or ignores the signal with
// "on_signal ignore".
std::string g_marker;
bool g_exit_on_signal = true;

void touch(const char *path) {
  const int fd = ::open(path, O_CREAT | O_WRONLY | O_CLOEXEC, 0644);
  if (fd >= 0)
    ::close(fd);
}

// Leaves a mark that the signal came (only async-signal-safe calls).
void mark_signal(int signal) {
  touch(g_marker.c_str());
  if (!g_exit_on_signal)
    return;
  std::signal(signal, SIG_DFL); // dies of it, as a process without handlers would
  std::raise(signal);
}

// An entry of "limits": a struct sequence with a sequence member, for the CLI's property syntax.
struct Limit {
  std::string name;
  double max = 0;
  std::vector<std::int32_t> steps;
};

class Faulty final : public Component {
public:
  explicit Faulty(const Context &context) : Component(context) {
    property("fault", fault_);
    // "chatter": a configure of N logs N numbered lines at once, each ~200 bytes, so that a test
    // fills a log past a small rotation bound when it chooses (the rotation test's).
    property("chatter", chatter_,
             [this](const std::uint32_t &, const std::uint32_t &lines) { chatter(lines); });
    // "deep_frame": a configure of N writes the node a request whose body nests N deep, as a
    // hostile component could (issue 37): the node must refuse it and live on.
    property("deep_frame", deep_frame_,
             [](const std::uint32_t &, const std::uint32_t &depth) { write_deep_frame(depth); });
    property("level", level_, [](const std::uint32_t &, const std::uint32_t &) {
      if (g_fault == "hang_at_configure")
        std::this_thread::sleep_for(std::chrono::hours(1)); // the fault itself: never answer
    });
    property("gains", gains_);
    struct_sequence_property("limits", limits_,
                             {{"limit::name", &Limit::name},
                              {"limit::max", &Limit::max},
                              {"limit::steps", &Limit::steps}});
    provides_port<rsca::port::Samples>("samples_in",
                                       [this](const rsca::port::Samples &) { ++received_; });
  }

private:
  // Straight on the link's descriptor, whole: the runtime writes nothing else meanwhile, its
  // reply to this configure going after the setter returns.
  static void write_deep_frame(std::uint32_t depth) {
    const std::string text =
        R"({"request": {"id": "deep", "target": "rsca/domain", "operation": "app.list", )"
        R"("sender": "x", "timeout_ms": 1000, "body": )" +
        std::string(depth, '[') + std::string(depth, ']') + "}}";
    const std::string wire = rsca::control::wire_of(text);
    std::size_t sent = 0;
    while (sent < wire.size()) {
      const ssize_t n =
          ::write(rsca::protocol::link::kNodeLinkFd, wire.data() + sent, wire.size() - sent);
      if (n <= 0)
        return;
      sent += static_cast<std::size_t>(n);
    }
  }

  void chatter(std::uint32_t lines) {
    const std::string padding(160, '.');
    for (std::uint32_t i = 0; i < lines; ++i)
      log().info("chatter {:06} {}", ++chattered_, padding);
  }

  Result start() override {
    if (g_fault == "crash_at_start")
      std::abort();
    if (g_fault == "exit_at_start")
      std::exit(3);
    return {};
  }

  std::string fault_ = "none";
  std::uint32_t level_ = 1;
  std::vector<double> gains_{1.0};
  std::vector<Limit> limits_;
  std::uint32_t chatter_ = 0;
  std::uint32_t deep_frame_ = 0;
  std::uint64_t chattered_ = 0; // lines logged so far, numbering the next
  std::uint64_t received_ = 0;
};

} // namespace

int main(int argc, char **argv) {
  g_fault = param_from(argc, argv, "fault", "none");
  if (g_fault == "mark_signals") { // with "on_signal ignore", only SIGKILL ends it
    g_marker = param_from(argc, argv, "marker", "/dev/null");
    g_exit_on_signal = param_from(argc, argv, "on_signal", "exit") != "ignore";
    std::signal(SIGINT, mark_signal);
    std::signal(SIGTERM, mark_signal);
    touch((g_marker + ".ready").c_str());
    for (;;)
      ::pause();
  }
  // "busy": a thread that burns a CPU for as long as the process runs (rsca top's test).
  if (g_fault == "busy")
    std::thread([] {
      volatile std::uint64_t spin = 0;
      for (;;)
        spin = spin + 1;
    }).detach();
  if (g_fault == "never_register")
    for (;;)
      std::this_thread::sleep_for(std::chrono::hours(1)); // the fault itself: never register
  return rsca::component::run<Faulty>(argc, argv);
}
