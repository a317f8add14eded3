#include "node/device_libraries.hpp"

#include <dlfcn.h>

#include <fmt/format.h>

#include "common/install_layout.hpp"
#include "node/device_export.hpp"

namespace rsca::node {

namespace fs = std::filesystem;

namespace {

// The SPD's first implementation whose code is a shared library, if any.
const profile::Implementation *library_implementation(const profile::SoftPkg &spd) {
  for (const auto &implementation : spd.implementations)
    if (implementation.code.type == profile::CodeType::SharedLibrary &&
        !implementation.code.file.name.empty())
      return &implementation;
  return nullptr;
}

} // namespace

// RTLD_LOCAL: two device libraries may define the same names (both may compile a helper in);
// what they share, the rsca runtime, comes from rsca-noded, which exports it.
std::optional<LoadFailure> DeviceLibraries::load(const fs::path &library,
                                                 DeviceRegistry &registry) {
  void *handle = dlopen(library.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
  if (handle == nullptr)
    return LoadFailure{library.string(), "",
                       fmt::format("cannot load {}: {}", library.string(), dlerror())};
  auto entry = reinterpret_cast<DeviceFactoriesExport>(dlsym(handle, kDeviceFactoriesSymbol));
  if (entry == nullptr)
    return LoadFailure{library.string(), kDeviceFactoriesSymbol,
                       fmt::format("{} exports no {} (declare its devices with RSCA_DEVICES)",
                                   library.string(), kDeviceFactoriesSymbol)};
  entry(&registry);
  return std::nullopt;
}

tl::expected<const DeviceFactory *, LoadFailure>
DeviceLibraries::factory_of(const profile::ResolvedSoftPkg &softpkg, DeviceRegistry &registry) {
  const auto &name = softpkg.spd->name;
  const auto *implementation = library_implementation(*softpkg.spd);
  if (implementation == nullptr)
    return tl::unexpected(LoadFailure{
        "", "",
        fmt::format("its SPD {} names no SharedLibrary implementation (a device is a library "
                    "rsca-noded loads)",
                    softpkg.spd_path.string())});
  const fs::path library =
      layout::resolve_code(implementation->code.file.name, softpkg.spd_path, folders_);
  auto [tried, first] = tried_.try_emplace(library);
  if (first)
    tried->second = load(library, registry);
  if (tried->second)
    return tl::unexpected(*tried->second);
  if (const auto *factory = registry.find(name))
    return factory;
  return tl::unexpected(LoadFailure{library.string(), kDeviceFactoriesSymbol,
                                    fmt::format("{} registers no device named {} (its {})",
                                                library.string(), name, kDeviceFactoriesSymbol)});
}

} // namespace rsca::node
