// How a node finds a device's implementation in the library its SPD names
// (node/device_libraries.hpp): each failure names the file and, where the file loads, the symbol.
#include <dlfcn.h>

#include <catch2/catch.hpp>

#include "node/device_export.hpp"
#include "node/device_libraries.hpp"
#include "temp_dir.hpp"

namespace {

namespace fs = std::filesystem;
using rsca::node::DeviceLibraries;
using rsca::node::DeviceRegistry;
using rsca::profile::CodeType;

const fs::path kLibraries = RSCA_LIBRARY_DIR;

// A device package named `name` whose one implementation is `library` of code type `type`, its
// SPD in `folder`.
rsca::profile::ResolvedSoftPkg softpkg(const std::string &name, const std::string &library,
                                       const fs::path &folder,
                                       CodeType type = CodeType::SharedLibrary) {
  auto spd = std::make_shared<rsca::profile::SoftPkg>();
  spd->name = name;
  rsca::profile::Implementation implementation;
  implementation.code.type = type;
  implementation.code.file.name = library;
  spd->implementations.push_back(implementation);
  rsca::profile::ResolvedSoftPkg out;
  out.spd_path = folder / (name + ".spd.xml");
  out.spd = spd;
  return out;
}

} // namespace

TEST_CASE("a device library that is not there fails naming the file", "[node][devices]") {
  rsca::test::TempDir dir;
  DeviceLibraries libraries({kLibraries});
  DeviceRegistry registry;
  auto factory =
      libraries.factory_of(softpkg("Gone", "librsca-no-such-device.so", dir.path()), registry);
  REQUIRE_FALSE(factory.has_value());
  CHECK_THAT(factory.error(), Catch::Contains("cannot load"));
  CHECK_THAT(factory.error(), Catch::Contains((dir.path() / "librsca-no-such-device.so").string()));
}

TEST_CASE("a library without the device symbol fails naming the file and the symbol",
          "[node][devices]") {
  rsca::test::TempDir dir;
  DeviceLibraries libraries({kLibraries});
  DeviceRegistry registry;
  // The XML reader module: a library rsca loads, found by name in rsca's library folder.
  auto factory =
      libraries.factory_of(softpkg("Reader", "librsca_xml_reader.so", dir.path()), registry);
  REQUIRE_FALSE(factory.has_value());
  CHECK_THAT(factory.error(), Catch::Contains((kLibraries / "librsca_xml_reader.so").string()));
  CHECK_THAT(factory.error(), Catch::Contains(rsca::node::kDeviceFactoriesSymbol));
}

TEST_CASE("a device library's devices are found by their SPD's name, the library loaded once",
          "[node][devices]") {
  rsca::test::TempDir dir;
  DeviceLibraries libraries({kLibraries});
  DeviceRegistry registry;
  const std::string library = "librsca-test-device.so";
  auto found = libraries.factory_of(softpkg("TestDevice", library, dir.path()), registry);
  REQUIRE(found.has_value());
  CHECK(*found == registry.find("TestDevice"));
  auto again = libraries.factory_of(softpkg("TestDevice", library, dir.path()), registry);
  REQUIRE(again.has_value());
  CHECK(*again == *found);
  // The library counts how often it was entered.
  void *loaded = dlopen((kLibraries / library).c_str(), RTLD_NOW | RTLD_NOLOAD);
  REQUIRE(loaded != nullptr);
  auto entries = reinterpret_cast<int (*)()>(dlsym(loaded, "rsca_test_device_entries"));
  REQUIRE(entries != nullptr);
  CHECK(entries() == 1);
  dlclose(loaded); // the reference RTLD_NOLOAD took

  auto other = libraries.factory_of(softpkg("Other", library, dir.path()), registry);
  REQUIRE_FALSE(other.has_value());
  CHECK_THAT(other.error(), Catch::Contains("registers no device named Other"));
  CHECK_THAT(other.error(), Catch::Contains(library));
}

TEST_CASE("a device whose SPD names no shared library has no implementation", "[node][devices]") {
  rsca::test::TempDir dir;
  DeviceLibraries libraries({kLibraries});
  DeviceRegistry registry;
  auto factory = libraries.factory_of(
      softpkg("GPP", "bin/rsca-gpp", dir.path(), CodeType::Executable), registry);
  REQUIRE_FALSE(factory.has_value());
  CHECK_THAT(factory.error(), Catch::Contains("names no SharedLibrary implementation"));
}
