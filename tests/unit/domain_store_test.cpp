// The DomainStore: what it keeps is there again when the file is opened anew, and what it was
// told to forget is not.
#include <unistd.h>

#include <filesystem>
#include <string>

#include <catch2/catch.hpp>

#include "domain/domain_store.hpp"

namespace fs = std::filesystem;
using rsca::domain::DomainStore;

namespace {

// A store file removed with it, also when the test fails.
struct TemporaryStore {
  fs::path file =
      fs::temp_directory_path() / ("rsca-domain-store-" + std::to_string(::getpid()) + ".sqlite");
  TemporaryStore() { fs::remove(file); }
  ~TemporaryStore() {
    std::error_code ignored;
    fs::remove(file, ignored);
  }
  TemporaryStore(const TemporaryStore &) = delete;
  TemporaryStore &operator=(const TemporaryStore &) = delete;
};

} // namespace

TEST_CASE("installed applications and runtime connections outlast the store's reopening",
          "[unit][domain-store]") {
  TemporaryStore temporary;
  {
    auto store = DomainStore::open(temporary.file);
    REQUIRE(store.has_value());
    REQUIRE(store->put_installed({"ProducerConsumer", "ProducerConsumer/pc.sad.xml"}).has_value());
    REQUIRE(store->put_connection({"kept", R"({"id":"kept"})"}).has_value());
    REQUIRE(store->put_connection({"dropped", R"({"id":"dropped"})"}).has_value());
    REQUIRE(store->put_connection({"kept", R"({"id":"kept","qos":{}})"}).has_value()); // replaced
    REQUIRE(store->remove_connection("dropped").has_value());
  }
  auto store = DomainStore::open(temporary.file);
  REQUIRE(store.has_value());
  auto installed = store->installed();
  REQUIRE(installed.has_value());
  REQUIRE(installed->size() == 1);
  CHECK(installed->front().sad == "ProducerConsumer/pc.sad.xml");
  auto connections = store->connections();
  REQUIRE(connections.has_value());
  REQUIRE(connections->size() == 1);
  CHECK(connections->front().id == "kept");
  CHECK(connections->front().request == R"({"id":"kept","qos":{}})");
}

TEST_CASE("a store that cannot be opened is an error naming the file", "[unit][domain-store]") {
  auto store = DomainStore::open("/proc/rsca-no-such-dir/domain.sqlite");
  REQUIRE_FALSE(store.has_value());
  CHECK_THAT(store.error().to_string(), Catch::Contains("/proc/rsca-no-such-dir/domain.sqlite"));
}

TEST_CASE("each start of the domain daemon counts one more incarnation, also after reopening",
          "[unit][domain-store]") {
  TemporaryStore temporary;
  std::uint64_t first = 0;
  {
    auto store = DomainStore::open(temporary.file);
    REQUIRE(store.has_value());
    auto a = store->next_incarnation();
    auto b = store->next_incarnation();
    REQUIRE(a.has_value());
    REQUIRE(b.has_value());
    CHECK(*b == *a + 1);
    first = *a;
  }
  auto reopened = DomainStore::open(temporary.file);
  REQUIRE(reopened.has_value());
  auto c = reopened->next_incarnation();
  REQUIRE(c.has_value());
  CHECK(*c == first + 2);
}
