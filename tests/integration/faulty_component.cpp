// rsca-test-faulty: a component that fails on purpose, as its "fault" exec parameter says, so
// that integration tests can see the domain roll a launch back. Test-only; never installed.
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>

#include "component/runtime.hpp"

namespace {

using rsca::component::Component;
using rsca::component::Context;
using rsca::component::Result;

// The fault is read from the command line before the runtime starts, because "never_register"
// must act before the component could announce itself.
std::string fault_from(int argc, char **argv) {
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "fault") == 0)
      return argv[i + 1];
  return "none";
}

std::string g_fault = "none";

class Faulty final : public Component {
public:
  explicit Faulty(const Context &context) : Component(context) {
    property("fault", fault_);
    property("level", level_, [](const std::uint32_t &, const std::uint32_t &) {
      if (g_fault == "hang_at_configure")
        std::this_thread::sleep_for(std::chrono::hours(1)); // the fault itself: never answer
    });
    provides_port<rsca::port::Samples>("samples_in",
                                       [this](const rsca::port::Samples &) { ++received_; });
  }

private:
  Result start() override {
    if (g_fault == "crash_at_start")
      std::abort();
    if (g_fault == "exit_at_start")
      std::exit(3);
    return {};
  }

  std::string fault_ = "none";
  std::uint32_t level_ = 1;
  std::uint64_t received_ = 0;
};

} // namespace

int main(int argc, char **argv) {
  g_fault = fault_from(argc, argv);
  if (g_fault == "never_register")
    for (;;)
      std::this_thread::sleep_for(std::chrono::hours(1)); // the fault itself: never register
  return rsca::component::run<Faulty>(argc, argv);
}
