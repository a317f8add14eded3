// Announcement slots (control/announcement_slots.hpp): the writer's reuse of slots, and the
// reader's mapping of slots back to the addresses they held, also when samples come by instance.
#include <optional>
#include <string>

#include <catch2/catch.hpp>

#include "control/announcement_slots.hpp"

using namespace rsca;

TEST_CASE("announcement slots are reused once withdrawn, lowest first", "[control]") {
  control::AnnouncerSlots slots;
  CHECK(slots.slot_for("a") == 0);
  CHECK(slots.slot_for("b") == 1);
  CHECK(slots.slot_for("c") == 2);
  CHECK(slots.slot_for("b") == 1); // an address keeps its slot while announced
  CHECK(slots.release("b") == 1u);
  CHECK(slots.release("a") == 0u);
  CHECK_FALSE(slots.release("a").has_value());
  CHECK(slots.slot_for("d") == 0);
  CHECK(slots.slot_for("e") == 1);
  CHECK(slots.slot_for("f") == 3);
  CHECK(slots.size() == 4);
}

TEST_CASE("a heard slot says which address went, and which one a new address replaced",
          "[control]") {
  control::HeardSlots heard;
  CHECK_FALSE(heard.heard("node1", 0, "app/a").has_value());
  CHECK_FALSE(heard.heard("node2", 0, "app/b").has_value()); // another announcer's slot 0
  CHECK_FALSE(heard.heard("node1", 0, "app/a").has_value()); // an update of the same address
  CHECK(heard.heard("node1", 0, "app/c") == std::optional<std::string>("app/a"));
  CHECK(heard.gone("node1", 0) == std::optional<std::string>("app/c"));
  CHECK_FALSE(heard.gone("node1", 0).has_value()); // not heard since
  CHECK(heard.gone("node2", 0) == std::optional<std::string>("app/b"));
  CHECK(heard.size() == 0);
}

TEST_CASE("an address heard in a new slot is not ended by its old slot's late end", "[control]") {
  control::HeardSlots heard;
  CHECK_FALSE(heard.heard("node1", 0, "app/a").has_value());
  // a withdrawn, slot 0 reused by b, a announced again in slot 1: taken by instance, slot 1 first.
  CHECK_FALSE(heard.heard("node1", 1, "app/a").has_value());
  CHECK_FALSE(heard.heard("node1", 0, "app/b").has_value()); // a lives in slot 1: not ended
  CHECK(heard.gone("node1", 0) == std::optional<std::string>("app/b"));
  CHECK(heard.gone("node1", 1) == std::optional<std::string>("app/a"));
  // The same order with a disposal in slot 0 instead of its reuse.
  CHECK_FALSE(heard.heard("node1", 0, "app/c").has_value());
  CHECK_FALSE(heard.heard("node1", 1, "app/c").has_value());
  CHECK_FALSE(heard.gone("node1", 0).has_value());
  CHECK(heard.gone("node1", 1) == std::optional<std::string>("app/c"));
}
