// How a node finds a device's implementation in the library its SPD names
// (node/device_libraries.hpp): each failure names the file and, where the file loads, the symbol.
#include <dlfcn.h>

#include <catch2/catch.hpp>

#include "node/device_export.hpp"
#include "node/device_libraries.hpp"
#include "temp_dir.hpp"

namespace {

namespace fs = std::filesystem;
using rsca::node::DeviceFactory;
using rsca::profile::CodeType;

const fs::path kLibraries = RSCA_LIBRARY_DIR;

// A node's libraries, its SPDs in a folder of their own and rsca's library folder the one to
// look in by name.
struct Node {
  rsca::test::TempDir spds;
  rsca::node::DeviceLibraries libraries{{kLibraries}};
  rsca::node::DeviceRegistry registry;

  // The factory of a device package `name` whose one implementation is `library` of code type
  // `type`.
  tl::expected<const DeviceFactory *, rsca::node::LoadFailure>
  factory_of(const std::string &name, const std::string &library,
             CodeType type = CodeType::SharedLibrary) {
    auto spd = std::make_shared<rsca::profile::SoftPkg>();
    spd->name = name;
    rsca::profile::Implementation implementation;
    implementation.code.type = type;
    implementation.code.file.name = library;
    spd->implementations.push_back(implementation);
    rsca::profile::ResolvedSoftPkg softpkg;
    softpkg.spd_path = spds.path() / (name + ".spd.xml");
    softpkg.spd = spd;
    return libraries.factory_of(softpkg, registry);
  }
};

} // namespace

TEST_CASE("a device library that is not there fails naming the file", "[node][devices]") {
  Node node;
  auto factory = node.factory_of("Gone", "librsca-no-such-device.so");
  REQUIRE_FALSE(factory.has_value());
  const auto &failure = factory.error();
  CHECK_THAT(failure.reason, Catch::Contains("cannot load"));
  const std::string file = (node.spds.path() / "librsca-no-such-device.so").string();
  CHECK_THAT(failure.reason, Catch::Contains(file));
  CHECK(failure.file == file);
  CHECK(failure.symbol.empty()); // never looked up: the file did not load
}

TEST_CASE("a library without the device symbol fails naming the file and the symbol",
          "[node][devices]") {
  Node node;
  // The XML reader module: a library rsca loads, found by name in rsca's library folder.
  auto factory = node.factory_of("Reader", "librsca_xml_reader.so");
  REQUIRE_FALSE(factory.has_value());
  const auto &failure = factory.error();
  CHECK_THAT(failure.reason, Catch::Contains((kLibraries / "librsca_xml_reader.so").string()));
  CHECK_THAT(failure.reason, Catch::Contains(rsca::node::kDeviceFactoriesSymbol));
  CHECK(failure.file == (kLibraries / "librsca_xml_reader.so").string());
  CHECK(failure.symbol == rsca::node::kDeviceFactoriesSymbol);
}

TEST_CASE("a device library's devices are found by their SPD's name, the library entered once",
          "[node][devices]") {
  Node node;
  const std::string library = "librsca-test-device.so";
  auto found = node.factory_of("TestDevice", library);
  REQUIRE(found.has_value());
  CHECK(*found == node.registry.find("TestDevice"));
  auto again = node.factory_of("TestDevice", library);
  REQUIRE(again.has_value());
  CHECK(*again == *found);
  // The library counts how often it was entered.
  void *loaded = dlopen((kLibraries / library).c_str(), RTLD_NOW | RTLD_NOLOAD);
  REQUIRE(loaded != nullptr);
  auto entries = reinterpret_cast<int (*)()>(dlsym(loaded, "rsca_test_device_entries"));
  REQUIRE(entries != nullptr);
  CHECK(entries() == 1);
  dlclose(loaded); // the reference RTLD_NOLOAD took

  auto other = node.factory_of("Other", library);
  REQUIRE_FALSE(other.has_value());
  CHECK_THAT(other.error().reason, Catch::Contains("registers no device named Other"));
  CHECK_THAT(other.error().reason, Catch::Contains(library));
  CHECK(other.error().file == (kLibraries / library).string());
  CHECK(other.error().symbol == rsca::node::kDeviceFactoriesSymbol);
}

TEST_CASE("a device whose SPD names no shared library has no implementation", "[node][devices]") {
  Node node;
  auto factory = node.factory_of("GPP", "bin/rsca-gpp", CodeType::Executable);
  REQUIRE_FALSE(factory.has_value());
  CHECK_THAT(factory.error().reason, Catch::Contains("names no SharedLibrary implementation"));
  CHECK(factory.error().file.empty());
}
