// rsca-test-supervisor: a component whose uses port "managed" (IDL:CF/Resource:1.0) is connected
// to other components' supported interface. Once started it configures each of them ("message"
// set to its own "set_message") and reads the value back, so that integration tests can see a
// componentsupportedinterface connection carry calls. Test-only; never installed.
#include "component/runtime.hpp"

namespace {

using rsca::component::Clock;
using rsca::component::Component;
using rsca::component::Context;
using rsca::component::ResourceUsesPort;
using rsca::component::Result;

class Supervisor final : public Component {
public:
  explicit Supervisor(const Context &context)
      : Component(context), managed_(resource_port("managed")) {
    property("set_message", set_message_);
    property("confirmed_message", confirmed_message_);
    property("supervised", supervised_);
  }

private:
  // Once per start, on the service thread: calls need not hold up the start itself.
  std::optional<Clock::duration> service() override {
    std::string message;
    {
      auto lock = lock_properties();
      message = set_message_;
    }
    if (auto ok = managed_.configure({{"message", message}}); !ok) {
      log().error("configuring the managed components failed: {}", ok.error().message);
      return std::nullopt;
    }
    auto values = managed_.query({"message"});
    if (!values) {
      log().error("querying the managed components failed: {}", values.error().message);
      return std::nullopt;
    }
    auto lock = lock_properties();
    supervised_ = static_cast<std::uint32_t>(values->size());
    for (const auto &[connection, properties] : *values)
      confirmed_message_ = properties.value("message", "");
    return std::nullopt;
  }

  ResourceUsesPort &managed_;
  std::string set_message_;
  std::string confirmed_message_;
  std::uint32_t supervised_ = 0;
};

} // namespace

int main(int argc, char **argv) {
  return rsca::component::run<Supervisor>(argc, argv);
}
