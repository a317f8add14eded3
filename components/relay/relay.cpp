// rsca-relay: forwards every sample sequence from `in` to `out` and counts them (forwarded). The
// building block of the synthetic applications tools/gen-app writes for tests and benchmarks.
#include <atomic>

#include "component/export.hpp"

namespace {

using rsca::component::Component;
using rsca::component::Context;

class Relay final : public Component {
public:
  explicit Relay(const Context &context)
      : Component(context), out_(uses_port<rsca::port::Samples>("out")) {
    property("forwarded", forwarded_);
    provides_port<rsca::port::Samples>("in", [this](const rsca::port::Samples &s) {
      if (out_.write(s))
        ++forwarded_;
    });
  }

private:
  rsca::component::UsesPort<rsca::port::Samples> &out_;
  std::atomic<std::uint64_t> forwarded_{0};
};

} // namespace

RSCA_COMPONENT(Relay)
