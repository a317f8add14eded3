#include "profile/profile_loader.hpp"

#include <algorithm>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "common/install_layout.hpp"
#include "profile/application_checks.hpp"
#include "profile/code_description.hpp"

namespace rsca::profile {

namespace fs = std::filesystem;

namespace {

// Splits checker findings: errors go to `errors`, warnings are returned.
std::vector<Diagnostic> split_findings(std::vector<Diagnostic> findings, Error &errors) {
  std::vector<Diagnostic> warnings;
  for (auto &d : findings) {
    if (d.severity == Severity::Warning)
      warnings.push_back(std::move(d));
    else
      errors.add(std::move(d));
  }
  return warnings;
}

// The descriptor name with its article: "ess" sounds a vowel, so "an SPD" but "a PRF".
std::string with_article(DescriptorType type) {
  const std::string_view name = to_string(type);
  return fmt::format("{} {}", name.front() == 'S' ? "an" : "a", name);
}

template <typename T>
DescriptorType descriptor_type_for() {
  return type_of(Descriptor(std::in_place_type<T>));
}

// A note at the place that referenced a file, added after the file's own diagnostics.
Error with_reference_note(Error error, const SourceLocation &referenced_at, const fs::path &file) {
  if (!referenced_at.file.empty())
    error.add({referenced_at, "invalid-ref",
               fmt::format("the file referenced here, {}, is invalid", file.string())});
  return error;
}

// Where a DCD's or DMD's manager SPD is, and the reference to check it from. rsca's daemons are
// the DeviceManager and the DomainManager, and their SPDs ship with rsca's profiles: a user's SDR
// root (one `rsca new device` made) names them as a REDHAWK root would, without holding them, so
// one missing there is looked up in rsca's default SDR root before it counts as missing. That one
// lies outside the user's root by design, so it is read as a file of rsca's own, referenced from
// nowhere in the user's root.
struct ManagerSpd {
  fs::path file;
  SourceLocation referenced_at;
};

ManagerSpd manager_spd(const SdrRoot &root, const LocalFile &named, const fs::path &referencing,
                       SdrTree tree) {
  ManagerSpd own{root.resolve(named.name, referencing, tree), named.where};
  std::error_code ec;
  if (fs::exists(own.file, ec) || named.name.empty() || named.name.front() != '/')
    return own;
  const fs::path shipped_root = layout::default_sdrroot();
  if (shipped_root.empty())
    return own;
  fs::path shipped = SdrRoot(shipped_root).resolve(named.name, referencing, tree);
  if (!fs::exists(shipped, ec))
    return own;
  return {std::move(shipped), {}};
}

// Whether a file could not be used only because it does not exist (what REDHAWK tolerates until
// the file is needed).
bool is_missing_file(const Error &error) {
  const auto &d = error.diagnostics();
  return d.size() == 1 && d.front().rule == "missing-file";
}

// The missing-file finding as the warning a package that names the file carries.
Diagnostic unavailable_warning(const Error &missing) {
  Diagnostic d = missing.diagnostics().front();
  d.severity = Severity::Warning;
  d.message += "; the package is read without it, but a component or device of it cannot run";
  return d;
}

void append_unique(std::vector<Diagnostic> &to, const std::vector<Diagnostic> &from) {
  for (const auto &d : from) {
    const bool seen = std::any_of(to.begin(), to.end(), [&](const Diagnostic &t) {
      return t.where.file == d.where.file && t.where.line == d.where.line &&
             t.where.column == d.where.column && t.rule == d.rule && t.message == d.message;
    });
    if (!seen)
      to.push_back(d);
  }
}

// A package whose SPD does not exist: what a SAD or DCD that names it holds in its place. It
// has no implementation and says why; whoever would run it refuses, naming the missing file.
std::shared_ptr<const ResolvedSoftPkg> missing_softpkg(const fs::path &spd_path,
                                                       const Error &missing) {
  auto pkg = std::make_shared<ResolvedSoftPkg>();
  pkg->spd_path = spd_path;
  auto spd = std::make_shared<SoftPkg>();
  spd->file = spd_path.string();
  spd->name = spd_path.filename().string();
  pkg->spd = std::move(spd);
  pkg->unavailable.push_back(missing.diagnostics().front());
  pkg->warnings.push_back(unavailable_warning(missing));
  return pkg;
}

// Under which tree an SPD's absolute names resolve: the tree it lives in.
SdrTree tree_of(const SdrRoot &root, const fs::path &file) {
  auto rel = file.lexically_relative(root.path());
  return (!rel.empty() && *rel.begin() == "dev") ? SdrTree::Dev : SdrTree::Dom;
}

} // namespace

const PropertyDefinition *ResolvedSoftPkg::find_property(std::string_view id) const {
  if (properties)
    if (const auto *d = properties->find(id))
      return d;
  for (const auto &impl : implementations)
    if (impl.properties)
      if (const auto *d = impl.properties->find(id))
        return d;
  return nullptr;
}

namespace {

void collect_files(const ResolvedSoftPkg &pkg, std::set<std::filesystem::path> &files) {
  if (pkg.sources.empty()) // an SPD that is not there: nothing of it to carry
    return;
  if (!files.insert(pkg.spd_path).second)
    return;
  if (pkg.properties)
    files.insert(pkg.properties->file);
  if (pkg.scd)
    files.insert(pkg.scd->file);
  for (const auto &impl : pkg.implementations) {
    if (impl.properties)
      files.insert(impl.properties->file);
    for (const auto &dep : impl.dependencies)
      collect_files(*dep.softpkg, files);
  }
}

// Code named by a relative path that stays beside or below its SPD; an absolute one is on the
// node itself (as REDHAWK allows), and one above the SPD's folder is not the package's to carry.
bool carried_code(const std::string &name) {
  const auto path = std::filesystem::path(name).lexically_normal();
  return !name.empty() && path.is_relative() && !path.empty() && *path.begin() != "..";
}

void collect_code(const ResolvedSoftPkg &pkg, std::set<std::filesystem::path> &files) {
  for (const auto &impl : pkg.implementations) {
    const auto &name = impl.implementation->code.file.name;
    std::error_code ec;
    if (const auto code = pkg.spd_path.parent_path() / name;
        carried_code(name) && std::filesystem::is_regular_file(code, ec))
      files.insert(code.lexically_normal());
    for (const auto &dep : impl.dependencies)
      collect_code(*dep.softpkg, files);
  }
}

} // namespace

std::set<std::filesystem::path> ResolvedApplication::code_files() const {
  std::set<std::filesystem::path> files;
  for (const auto &[id, pkg] : component_files)
    collect_code(*pkg, files);
  return files;
}

std::set<std::filesystem::path> ResolvedApplication::files() const {
  std::set<std::filesystem::path> files{sad_path};
  for (const auto &[id, pkg] : component_files)
    collect_files(*pkg, files);
  return files;
}

const ResolvedSoftPkg *ResolvedApplication::softpkg_of(const ComponentPlacement &placement) const {
  auto it = component_files.find(placement.componentfile_ref);
  return it == component_files.end() ? nullptr : it->second.get();
}

ProfileLoader::ProfileLoader(std::optional<fs::path> sdrroot, std::optional<fs::path> fallback)
    : sdrroot_(std::move(sdrroot)), fallback_(std::move(fallback)) {}

Expected<SdrRoot> ProfileLoader::root_for(const fs::path &file) const {
  if (sdrroot_) {
    SdrRoot given(fs::absolute(*sdrroot_).lexically_normal());
    // rsca's own profiles (the managers' SPDs, manager_spd()) are read within their own root.
    if (given.contains(file))
      return given;
    if (const fs::path shipped = layout::default_sdrroot();
        !shipped.empty() && SdrRoot(shipped).contains(file))
      return SdrRoot(shipped);
    return given;
  }
  if (auto root = SdrRoot::locate(file, std::nullopt, fallback_))
    return *root;
  return make_error({file.string(), 0, 0}, "sdrroot", std::string(kNoSdrRoot));
}

Expected<std::shared_ptr<const Descriptor>>
ProfileLoader::cached_descriptor(const fs::path &file, const SourceLocation &referenced_at) {
  if (!xml_reader_) {
    auto reader = XmlReader::acquire();
    if (!reader)
      return tl::unexpected(reader.error());
    xml_reader_ = std::move(*reader);
  }
  const fs::path key = key_of(file);
  std::error_code ec;
  if (!referenced_at.file.empty()) {
    auto root = root_for(referenced_at.file);
    if (root && !root->contains(key))
      return make_error(referenced_at, "outside-sdrroot",
                        fmt::format("the file named here, {}, lies outside the SDR root {}",
                                    key.string(), root->path().string()));
  }
  if (!referenced_at.file.empty() && !fs::is_regular_file(key, ec))
    return make_error(referenced_at, "missing-file",
                      fmt::format("the file named here does not exist: {}", key.string()));
  auto it = files_.find(key);
  if (it == files_.end()) {
    stamps_[key] = stamp_of(key);
    auto read = read_descriptor(key).map(
        [](Descriptor d) { return std::make_shared<const Descriptor>(std::move(d)); });
    it = files_.emplace(key, std::move(read)).first;
  }
  if (!it->second)
    return tl::unexpected(with_reference_note(it->second.error(), referenced_at, key));
  return *it->second;
}

fs::path ProfileLoader::key_of(const fs::path &file) {
  return fs::absolute(file).lexically_normal();
}

SourceFile ProfileLoader::source_file(const fs::path &file) const {
  const fs::path key = key_of(file);
  auto it = stamps_.find(key);
  return {key.string(), it == stamps_.end() ? std::nullopt : it->second};
}

template <typename T>
Expected<std::shared_ptr<const T>> ProfileLoader::cached_source(const fs::path &file,
                                                                const SourceLocation &referenced_at,
                                                                std::vector<SourceFile> &sources) {
  auto part = cached<T>(file, referenced_at);
  if (part)
    sources.push_back(source_file(file));
  return part;
}

template <typename T>
Expected<std::shared_ptr<const T>> ProfileLoader::cached(const fs::path &file,
                                                         const SourceLocation &referenced_at) {
  auto descriptor = cached_descriptor(file, referenced_at);
  if (!descriptor)
    return tl::unexpected(descriptor.error());
  const T *typed = std::get_if<T>(descriptor->get());
  if (typed == nullptr)
    return make_error(
        referenced_at.file.empty() ? SourceLocation{file.string(), 0, 0} : referenced_at,
        "wrong-descriptor",
        fmt::format("expected {}, but {} is {}", with_article(descriptor_type_for<T>()),
                    file.string(), with_article(type_of(**descriptor))));
  return std::shared_ptr<const T>(*descriptor, typed);
}

Expected<std::shared_ptr<const ResolvedSoftPkg>>
ProfileLoader::load_softpkg(const fs::path &spd_file) {
  return softpkg(spd_file, {});
}

Expected<std::shared_ptr<const ResolvedSoftPkg>>
ProfileLoader::softpkg(const fs::path &spd_file, const SourceLocation &referenced_at) {
  const fs::path key = key_of(spd_file);
  if (auto cycle = std::find(resolving_.begin(), resolving_.end(), key);
      cycle != resolving_.end()) {
    std::vector<std::string> chain;
    for (auto it = cycle; it != resolving_.end(); ++it)
      chain.push_back(it->filename().string());
    chain.push_back(key.filename().string());
    return make_error(referenced_at, "dependency-cycle",
                      fmt::format("softpkg dependency cycle: {}", fmt::join(chain, " -> ")));
  }
  if (auto it = softpkgs_.find(key); it != softpkgs_.end()) {
    if (!it->second)
      return tl::unexpected(with_reference_note(it->second.error(), referenced_at, key));
    return it->second;
  }

  auto spd = cached<SoftPkg>(key, referenced_at);
  if (!spd)
    return tl::unexpected(spd.error());
  auto root = root_for(key);
  if (!root)
    return tl::unexpected(root.error());

  resolving_.push_back(key);
  Error errors;
  auto resolved = std::make_shared<ResolvedSoftPkg>();
  resolved->spd_path = key;
  resolved->spd = *spd;
  resolved->sources.push_back(source_file(key));
  const SdrTree own_tree = tree_of(*root, key);
  auto file_of = [&](const LocalFile &f) { return root->resolve(f.name, key, own_tree); };
  append_unique(resolved->warnings, (*spd)->warnings);
  // A part that is there is kept with its warnings; a missing one makes the package unavailable.
  auto keep = [&](auto part, auto &into) {
    if (part) {
      into = *part;
      append_unique(resolved->warnings, (*part)->warnings);
    } else if (is_missing_file(part.error())) {
      resolved->unavailable.push_back(part.error().diagnostics().front());
      resolved->warnings.push_back(unavailable_warning(part.error()));
    } else {
      errors.append(part.error());
    }
  };
  if (const auto &pf = (*spd)->property_file)
    keep(cached_source<Properties>(file_of(*pf), pf->where, resolved->sources),
         resolved->properties);
  if (const auto &d = (*spd)->descriptor)
    keep(cached_source<SoftwareComponent>(file_of(*d), d->where, resolved->sources), resolved->scd);
  for (const auto &impl : (*spd)->implementations) {
    ResolvedImplementation ri{&impl, nullptr, {}};
    if (impl.property_file)
      keep(cached_source<Properties>(file_of(*impl.property_file), impl.property_file->where,
                                     resolved->sources),
           ri.properties);
    for (const auto &ref : impl.softpkg_dependencies) {
      // Shared libraries live in dom/deps whichever tree the package is in, as in REDHAWK.
      auto dep = softpkg(root->resolve(ref.file.name, key, SdrTree::Dom), ref.file.where);
      if (!dep) {
        if (is_missing_file(dep.error())) {
          resolved->unavailable.push_back(dep.error().diagnostics().front());
          resolved->warnings.push_back(unavailable_warning(dep.error()));
        } else {
          errors.append(dep.error());
        }
        continue;
      }
      append_unique(resolved->warnings, (*dep)->warnings);
      append_unique(resolved->unavailable, (*dep)->unavailable);
      if (ref.implref && (*dep)->spd->find_implementation(*ref.implref) == nullptr) {
        std::vector<std::string> ids;
        for (const auto &i : (*dep)->spd->implementations)
          ids.push_back(i.id);
        errors.add({ref.implref_where, "dangling-ref",
                    fmt::format("implref \"{}\" names no implementation of {} (it has: {})",
                                *ref.implref, (*dep)->spd->name, fmt::join(ids, ", "))});
      }
      ri.dependencies.push_back({*dep, ref.implref});
    }
    resolved->implementations.push_back(std::move(ri));
  }
  resolving_.pop_back();

  Expected<std::shared_ptr<const ResolvedSoftPkg>> result =
      errors.empty() ? Expected<std::shared_ptr<const ResolvedSoftPkg>>(std::move(resolved))
                     : tl::unexpected(errors);
  softpkgs_.emplace(key, result);
  if (!result)
    return tl::unexpected(with_reference_note(result.error(), referenced_at, key));
  return result;
}

Expected<ResolvedApplication> ProfileLoader::load_application(const fs::path &sad_file) {
  auto root = root_for(sad_file);
  if (!root)
    return tl::unexpected(root.error());
  auto sad = cached<SoftwareAssembly>(sad_file, {});
  if (!sad)
    return tl::unexpected(sad.error());
  ResolvedApplication app{fs::absolute(sad_file).lexically_normal(), *sad, {}, {}, {}};
  Error errors;
  for (const auto &cf : (*sad)->component_files) {
    const fs::path spd_path = root->resolve(cf.file.name, app.sad_path, SdrTree::Dom);
    auto spd = softpkg(spd_path, cf.file.where);
    if (spd)
      app.component_files.emplace(cf.id, *spd);
    else if (is_missing_file(spd.error()))
      app.component_files.emplace(cf.id, missing_softpkg(spd_path, spd.error()));
    else
      errors.append(spd.error());
  }
  app.tolerated = (*sad)->warnings;
  for (const auto &cf : (*sad)->component_files) // in the SAD's order
    if (auto it = app.component_files.find(cf.id); it != app.component_files.end())
      append_unique(app.tolerated, it->second->warnings);
  if (errors.empty())
    app.warnings = split_findings(check_application(app, app.tolerated), errors);
  if (!errors.empty())
    return tl::unexpected(errors);
  return app;
}

Expected<ResolvedNode> ProfileLoader::load_node(const fs::path &dcd_file) {
  auto root = root_for(dcd_file);
  if (!root)
    return tl::unexpected(root.error());
  auto dcd = cached<DeviceConfiguration>(dcd_file, {});
  if (!dcd)
    return tl::unexpected(dcd.error());
  ResolvedNode node{fs::absolute(dcd_file).lexically_normal(), *dcd, {}, {}, (*dcd)->warnings};
  Error errors;
  // rsca-noded is the DeviceManager: its SPD is checked when it is there, and nothing needs it.
  if (const auto &mgr = (*dcd)->device_manager_softpkg; !mgr.name.empty()) {
    const ManagerSpd where = manager_spd(*root, mgr, node.dcd_path, SdrTree::Dev);
    auto spd = softpkg(where.file, where.referenced_at);
    if (!spd && is_missing_file(spd.error())) {
      Diagnostic d = spd.error().diagnostics().front();
      d.severity = Severity::Warning;
      d.message += "; rsca-noded is the DeviceManager and does not need it";
      node.tolerated.push_back(std::move(d));
    } else if (!spd)
      errors.append(spd.error());
  }
  for (const auto &placement : (*dcd)->placements) {
    ResolvedDevicePlacement device{&placement, nullptr, nullptr};
    if (const ComponentFile *cf = (*dcd)->find_component_file(placement.componentfile_ref)) {
      const fs::path spd_path = root->resolve(cf->file.name, node.dcd_path, SdrTree::Dev);
      auto spd = softpkg(spd_path, cf->file.where);
      if (spd)
        device.softpkg = *spd;
      else if (is_missing_file(spd.error()))
        device.softpkg = missing_softpkg(spd_path, spd.error());
      else
        errors.append(spd.error());
    }
    if (placement.device_pkg_file) {
      const auto &f = *placement.device_pkg_file;
      auto dpd = cached<DevicePkg>(root->resolve(f.name, node.dcd_path, SdrTree::Dev), f.where);
      if (dpd) {
        device.device_pkg = *dpd;
        append_unique(node.tolerated, (*dpd)->warnings);
      } else if (is_missing_file(dpd.error())) {
        // Its hardware description: nothing rsca runs needs it.
        Diagnostic d = dpd.error().diagnostics().front();
        d.severity = Severity::Warning;
        d.message += "; the device is described without it";
        node.tolerated.push_back(std::move(d));
      } else {
        errors.append(dpd.error());
      }
    }
    if (device.softpkg)
      append_unique(node.tolerated, device.softpkg->warnings);
    node.devices.push_back(std::move(device));
  }
  if (errors.empty())
    node.warnings = split_findings(check_node(node, node.tolerated), errors);
  if (!errors.empty())
    return tl::unexpected(errors);
  return node;
}

Expected<DomainManagerConfiguration> ProfileLoader::load_domain(const fs::path &dmd_file) {
  auto root = root_for(dmd_file);
  if (!root)
    return tl::unexpected(root.error());
  auto dmd = cached<DomainManagerConfiguration>(dmd_file, {});
  if (!dmd)
    return tl::unexpected(dmd.error());
  // rsca-domaind is the DomainManager: its SPD is checked when it is there, and nothing needs it.
  const auto &mgr = (*dmd)->domain_manager_softpkg;
  const ManagerSpd where = manager_spd(*root, mgr, fs::absolute(dmd_file), SdrTree::Dom);
  auto spd = softpkg(where.file, where.referenced_at);
  if (!spd && !is_missing_file(spd.error()))
    return tl::unexpected(spd.error());
  return **dmd;
}

Expected<ValidatedDescriptor> ProfileLoader::validate(const fs::path &file) {
  auto descriptor = cached_descriptor(file, {});
  if (!descriptor)
    return tl::unexpected(descriptor.error());
  // Its own warnings first, then those of what it references.
  ValidatedDescriptor result{**descriptor,
                             std::visit([](const auto &d) { return d.warnings; }, **descriptor)};
  auto keep = [&](auto loaded, auto warnings_of) -> Expected<ValidatedDescriptor> {
    if (!loaded)
      return tl::unexpected(loaded.error());
    append_unique(result.warnings, warnings_of(*loaded));
    return result;
  };
  auto nothing_more = [](const auto &) { return std::vector<Diagnostic>{}; };
  switch (type_of(**descriptor)) {
  case DescriptorType::SAD: {
    auto app = load_application(file);
    if (auto misfits = app ? code_refusals(*app) : std::vector<Diagnostic>{}; !misfits.empty())
      return tl::unexpected(Error(std::move(misfits))); // what a launch refuses too
    return keep(std::move(app), [](const ResolvedApplication &a) {
      auto all = a.warnings;
      append_unique(all, a.tolerated);
      return all;
    });
  }
  case DescriptorType::DCD:
    return keep(load_node(file), [](const ResolvedNode &n) {
      auto all = n.warnings;
      append_unique(all, n.tolerated);
      return all;
    });
  case DescriptorType::SPD: {
    auto pkg = load_softpkg(file);
    if (auto misfits = pkg ? code_refusals(**pkg) : std::vector<Diagnostic>{}; !misfits.empty())
      return tl::unexpected(Error(std::move(misfits)));
    return keep(std::move(pkg), [](const auto &p) { return p->warnings; });
  }
  case DescriptorType::DMD:
    return keep(load_domain(file), nothing_more);
  case DescriptorType::SCD:
  case DescriptorType::PRF:
  case DescriptorType::DPD:
    break;
  }
  return result;
}

} // namespace rsca::profile
