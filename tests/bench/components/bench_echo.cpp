// rsca-bench-echo: the echoing half of the port-latency benchmark (tests/bench/port_bench.py):
// every sample that arrives on `in` is written back unchanged on `out`, from the receive
// callback, at once.
#include <atomic>

#include "component/runtime.hpp"

namespace {

using rsca::component::Component;
using rsca::component::Context;
using rsca::port::Samples;

class Echo final : public Component {
public:
  explicit Echo(const Context &context) : Component(context), out_(uses_port<Samples>("out")) {
    property("echoed", echoed_);
    provides_port<Samples>("in", [this](const Samples &sample) {
      if (auto written = out_.write(sample); written)
        ++echoed_;
      else
        log().warn("{}", written.error());
    });
  }

private:
  rsca::component::UsesPort<Samples> &out_;
  std::atomic<std::uint64_t> echoed_{0};
};

} // namespace

int main(int argc, char **argv) {
  return rsca::component::run<Echo>(argc, argv);
}
