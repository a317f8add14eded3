// Loads profiles with everything they reference — a SAD with its SPDs, SCDs, PRFs and softpkg
// dependencies; a DCD with its device packages — checks references across files, and caches
// each file so a package shared by many applications is read once.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common/diagnostic.hpp"
#include "profile/descriptor.hpp"
#include "profile/file_stamp.hpp"
#include "profile/sdr_root.hpp"
#include "profile/xml_reader.hpp"

namespace rsca::profile {

struct ResolvedSoftPkg;

// How deep softpkg dependencies may nest: the planner matches them, the FileManager delivers them,
// to the same depth.
inline constexpr int kMaxSoftpkgDependencyDepth = 32;

struct ResolvedDependency {
  std::shared_ptr<const ResolvedSoftPkg> softpkg;
  std::optional<std::string> implref;
};

struct ResolvedImplementation {
  const Implementation *implementation = nullptr; // points into the SPD it belongs to
  std::shared_ptr<const Properties> properties;   // implementation-specific PRF, may be null
  std::vector<ResolvedDependency> dependencies;
};

struct ResolvedSoftPkg {
  std::filesystem::path spd_path;
  std::shared_ptr<const SoftPkg> spd;
  std::shared_ptr<const Properties> properties; // may be null
  std::shared_ptr<const SoftwareComponent> scd; // may be null (libraries have none)
  std::vector<ResolvedImplementation> implementations;
  // The files it was read from (its SPD, PRFs and SCD), each stamped before it was read.
  std::vector<SourceFile> sources;
  // What reading it and its dependencies tolerated, unavailable files included.
  std::vector<Diagnostic> warnings;
  // Files it names that do not exist (a PRF, the SCD, a dependency): as in REDHAWK, the package
  // reads and validates without them, but a component of it cannot be launched, nor a device
  // of it started. Each is located where the file is named.
  std::vector<Diagnostic> unavailable;

  // The definition of property `id` in the SPD's PRF or any implementation's PRF.
  const PropertyDefinition *find_property(std::string_view id) const;
};

struct ResolvedApplication {
  std::filesystem::path sad_path;
  std::shared_ptr<const SoftwareAssembly> sad;
  std::map<std::string, std::shared_ptr<const ResolvedSoftPkg>> component_files; // by id
  std::vector<Diagnostic> warnings; // wiring findings; a launch treats them as errors
  // What reading its files tolerated (REDHAWK forms read with a warning, files missing that the
  // launch of some component would need): only `--strict` refuses them.
  std::vector<Diagnostic> tolerated;

  const ResolvedSoftPkg *softpkg_of(const ComponentPlacement &placement) const;
  // Every profile file the application names: its SAD, and each package's SPD, SCD and PRFs,
  // softpkg dependencies included (what an install carries to the domain).
  std::set<std::filesystem::path> files() const;
  // The code files its packages name that lie beside their SPDs as regular files (a component
  // built and installed into an SDR root): an install carries them too. Code elsewhere, or a
  // folder, is the domain's to find in its exec path.
  std::set<std::filesystem::path> code_files() const;
};

struct ResolvedDevicePlacement {
  const ComponentPlacement *placement = nullptr; // points into the DCD
  std::shared_ptr<const ResolvedSoftPkg> softpkg;
  std::shared_ptr<const DevicePkg> device_pkg; // when the placement names a DPD
};

struct ResolvedNode {
  std::filesystem::path dcd_path;
  std::shared_ptr<const DeviceConfiguration> dcd;
  std::vector<ResolvedDevicePlacement> devices;
  std::vector<Diagnostic> warnings;
  std::vector<Diagnostic> tolerated; // as ResolvedApplication::tolerated
};

// A descriptor that passed validation, with the warnings found on the way.
struct ValidatedDescriptor {
  Descriptor descriptor;
  std::vector<Diagnostic> warnings;
};

// Reading needs the XML reader module, loaded while any loader that has read a file lives: a
// process that reads its profiles once (a node daemon, a component) lets its loader go.
class ProfileLoader {
public:
  // `sdrroot`: where absolute profile paths resolve; when empty, found from each file's location
  // (SdrRoot::locate, `fallback` standing for SDRROOT).
  explicit ProfileLoader(std::optional<std::filesystem::path> sdrroot = std::nullopt,
                         std::optional<std::filesystem::path> fallback = std::nullopt);

  Expected<ResolvedApplication> load_application(const std::filesystem::path &sad_file);
  Expected<ResolvedNode> load_node(const std::filesystem::path &dcd_file);
  Expected<std::shared_ptr<const ResolvedSoftPkg>>
  load_softpkg(const std::filesystem::path &spd_file);
  Expected<DomainManagerConfiguration> load_domain(const std::filesystem::path &dmd_file);

  // Reads any descriptor and resolves what it references (the whole check `rsca validate` does).
  Expected<ValidatedDescriptor> validate(const std::filesystem::path &file);

private:
  Expected<SdrRoot> root_for(const std::filesystem::path &file) const;
  Expected<std::shared_ptr<const ResolvedSoftPkg>> softpkg(const std::filesystem::path &spd_file,
                                                           const SourceLocation &referenced_at);
  Expected<std::shared_ptr<const Descriptor>>
  cached_descriptor(const std::filesystem::path &file, const SourceLocation &referenced_at);
  // Files are known by their absolute, normal path.
  static std::filesystem::path key_of(const std::filesystem::path &file);
  // `file` as read, with the stamp taken before reading it.
  SourceFile source_file(const std::filesystem::path &file) const;
  // cached<T>, and on success `file` as read added to `sources`.
  template <typename T>
  Expected<std::shared_ptr<const T>> cached_source(const std::filesystem::path &file,
                                                   const SourceLocation &referenced_at,
                                                   std::vector<SourceFile> &sources);
  template <typename T>
  Expected<std::shared_ptr<const T>> cached(const std::filesystem::path &file,
                                            const SourceLocation &referenced_at);

  std::optional<std::filesystem::path> sdrroot_;
  std::optional<std::filesystem::path> fallback_;
  std::map<std::filesystem::path, Expected<std::shared_ptr<const Descriptor>>> files_;
  std::map<std::filesystem::path, std::optional<FileStamp>> stamps_; // taken before each read
  std::map<std::filesystem::path, Expected<std::shared_ptr<const ResolvedSoftPkg>>> softpkgs_;
  std::vector<std::filesystem::path> resolving_; // SPDs being resolved, to find cycles
  // Held from the first file read to the loader's end: its files share one load of the reader.
  std::shared_ptr<XmlReader> xml_reader_;
};

} // namespace rsca::profile
