// The ApplicationRegistry: a launching application holds its name and its installed
// application, is not found until committed, and its state changes only through the registry.
#include <catch2/catch.hpp>

#include "domain/application_factory.hpp"
#include "domain/application_registry.hpp"

using rsca::control::Status;
using rsca::domain::Application;
using rsca::domain::ApplicationRegistry;
using rsca::domain::ComponentState;

namespace {

std::shared_ptr<Application> application(const std::string &name, const std::string &installed) {
  auto app = std::make_shared<Application>();
  app->name = name;
  app->installed = installed;
  rsca::domain::ComponentInstance c;
  c.id = "Producer_1";
  c.state = ComponentState::Running;
  c.pid = 42;
  app->components.push_back(c);
  return app;
}

} // namespace

TEST_CASE("a launching application holds its name but is not found until committed",
          "[unit][application-registry]") {
  ApplicationRegistry registry;
  auto name = registry.reserve("PC", /*exact=*/false, "ProducerConsumer");
  REQUIRE(name.has_value());
  CHECK(*name == "PC");
  CHECK(registry.launching("ProducerConsumer"));
  CHECK_FALSE(registry.launching("Other"));
  // Not found, not updatable, not listed: nothing reads a half-made application.
  CHECK(registry.find("PC").error().status == Status::NotFound);
  CHECK_FALSE(registry.update("PC", [](Application &) { FAIL("updated while launching"); }));
  CHECK(registry.snapshots().empty());
  CHECK(registry.running_from("ProducerConsumer").empty());
  // The name is taken: an exact request is refused, another gets the next free name.
  CHECK(registry.reserve("PC", /*exact=*/true, "ProducerConsumer").error().status ==
        Status::Rejected);
  CHECK(registry.reserve("PC", /*exact=*/false, "ProducerConsumer").value() == "PC_2");

  registry.commit(application("PC", "ProducerConsumer"));
  REQUIRE(registry.find("PC").has_value());
  CHECK(registry.running_from("ProducerConsumer") == std::vector<std::string>{"PC"});
  registry.drop("PC_2");
  CHECK_FALSE(registry.launching("ProducerConsumer"));
}

TEST_CASE("a dropped reservation frees the name, drop never removes a running application",
          "[unit][application-registry]") {
  ApplicationRegistry registry;
  REQUIRE(registry.reserve("A", true, "X").has_value());
  registry.drop("A");
  CHECK_FALSE(registry.launching("X"));
  CHECK(registry.reserve("A", true, "X").has_value());
  registry.commit(application("A", "X"));
  registry.drop("A"); // a late drop of a committed name
  CHECK(registry.find("A").has_value());
}

TEST_CASE("state changes go through update and readers get copies",
          "[unit][application-registry]") {
  ApplicationRegistry registry;
  REQUIRE(registry.reserve("A", true, "X").has_value());
  registry.commit(application("A", "X"));
  auto before = registry.snapshot("A");
  REQUIRE(before.has_value());
  CHECK(
      registry.update("A", [](Application &a) { a.components[0].state = ComponentState::Exited; }));
  CHECK(before->components[0].state == ComponentState::Running); // a copy: unchanged
  CHECK(registry.snapshot("A")->components[0].state == ComponentState::Exited);
  CHECK(rsca::domain::state_of(*registry.snapshot("A")) == "degraded");
  CHECK(rsca::domain::exited_components(*registry.snapshot("A")) ==
        std::vector<std::string>{"Producer_1"});
}

TEST_CASE("a removed application is found no more, and its handle stays usable",
          "[unit][application-registry]") {
  ApplicationRegistry registry;
  REQUIRE(registry.reserve("A", true, "X").has_value());
  registry.commit(application("A", "X"));
  auto found = registry.find("A");
  REQUIRE(found.has_value());
  auto removed = registry.remove("A");
  REQUIRE(removed.has_value());
  CHECK(removed->app == found->app);
  CHECK(registry.find("A").error().status == Status::NotFound);
  CHECK_FALSE(registry.remove("A").has_value());
  CHECK_FALSE(registry.update("A", [](Application &) {}));
}

TEST_CASE("launch identities and the incarnation read back from an address",
          "[unit][application-registry]") {
  using rsca::protocol::incarnation_of;
  const rsca::domain::LaunchIdentity launch{7, 12};
  CHECK(rsca::protocol::to_string(launch) == "7.12");
  CHECK(incarnation_of("rsca/component/PC.7.12/Producer_1") == 7u);
  CHECK(incarnation_of("rsca/component/rh.FM.demo.3.1/X") == 3u); // dots in the name
  CHECK(incarnation_of("rsca/host/PC.9.1/node1:GPP_1") == 9u);
  CHECK_FALSE(incarnation_of("rsca/node/node1").has_value());
  CHECK_FALSE(incarnation_of("rsca/component/PC.12/Producer_1").has_value()); // one number
  CHECK_FALSE(incarnation_of("rsca/component/PC.x.1/Producer_1").has_value());
}
