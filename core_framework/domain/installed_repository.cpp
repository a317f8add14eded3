#include "domain/installed_repository.hpp"

#include <unistd.h>

#include <atomic>
#include <fstream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "common/names.hpp"
#include "content/base64.hpp"
#include "profile/application_checks.hpp"
#include "profile/runtime_model.hpp"

namespace rsca::domain {
namespace {

namespace fs = std::filesystem;
using control::CallResult;
using control::Status;

// Whether `path` lies strictly inside `dir`. Lexical: the repository's own folders hold no links
// (files arrive as contents and are written as regular files).
bool inside(const fs::path &dir, const fs::path &path) {
  const fs::path rel = path.lexically_normal().lexically_relative(dir.lexically_normal());
  return !rel.empty() && rel != "." && *rel.begin() != "..";
}

// Removes a folder of the repository, and nothing outside it whatever it is asked.
void remove_inside(const fs::path &root, const fs::path &dir) {
  if (!inside(root, dir)) {
    spdlog::error("not removing {}: it is not inside the repository {}", dir.string(),
                  root.string());
    return;
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
  if (ec)
    spdlog::warn("removing {}: {}", dir.string(), ec.message());
}

// A folder of the repository that is removed when it goes out of scope, unless kept.
class ScopedFolder {
public:
  ScopedFolder(fs::path root, fs::path dir) : root_(std::move(root)), dir_(std::move(dir)) {}
  ~ScopedFolder() {
    if (!dir_.empty())
      remove_inside(root_, dir_);
  }
  ScopedFolder(const ScopedFolder &) = delete;
  ScopedFolder &operator=(const ScopedFolder &) = delete;
  const fs::path &path() const { return dir_; }
  void keep() { dir_.clear(); }
  void reset(fs::path dir) { dir_ = std::move(dir); }

private:
  fs::path root_;
  fs::path dir_;
};

// A file's path from a client, which must stay inside the install: relative, no "..".
std::optional<fs::path> safe_relative(const std::string &path) {
  fs::path p = fs::path(path).lexically_normal();
  if (p.empty() || p.is_absolute() || *p.begin() == "..")
    return std::nullopt;
  return p;
}

// A folder name no other install (of this or a concurrent daemon) has.
std::string unique_name(std::string_view what) {
  static std::atomic<std::uint64_t> counter{0};
  return fmt::format("{}-{}-{}", what, ::getpid(), ++counter);
}

auto over_budget(const InstallFile &f) {
  return control::call_error(
      Status::BadRequest, fmt::format("file {}: an install carries at most {} MiB in all",
                                      excerpt(f.path), protocol::domain::kMaxInstallBytes >> 20U));
}

// A base64 file's bytes, decoded only once its size is known to fit `budget`.
CallResult<std::string> decoded(const InstallFile &f, std::uint64_t budget) {
  const auto size = content::base64_decoded_size(f.content);
  if (!size)
    return control::call_error(Status::BadRequest,
                               fmt::format("file {}: its content is not base64", excerpt(f.path)));
  if (*size > budget)
    return over_budget(f);
  return *content::base64_decode(f.content);
}

CallResult<void> write_file(const fs::path &file, std::string_view bytes, bool executable) {
  std::error_code ec;
  fs::create_directories(file.parent_path(), ec);
  std::ofstream out(file, std::ios::binary);
  out << bytes;
  out.close();
  if (!ec && out && executable)
    fs::permissions(file, fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec,
                    fs::perm_options::add, ec);
  if (ec || !out)
    return control::call_error(Status::Failed,
                               fmt::format("writing {} into the repository: {}", file.string(),
                                           ec ? ec.message() : std::strerror(errno)));
  return {};
}

CallResult<void> write_files(const fs::path &dir, const std::vector<InstallFile> &files) {
  std::uint64_t budget = protocol::domain::kMaxInstallBytes;
  for (const auto &f : files) {
    auto rel = safe_relative(f.path);
    if (!rel)
      return control::call_error(
          Status::BadRequest,
          fmt::format("file path \"{}\" is not inside an SDR root (an install names each "
                      "file relative to the SDR root it comes from)",
                      excerpt(f.path, protocol::domain::kMaxInstallPath)));
    std::string decoded_bytes;
    std::string_view bytes = f.content;
    if (f.encoding.value_or(protocol::domain::FileEncoding::Text) ==
        protocol::domain::FileEncoding::Base64) {
      auto code = decoded(f, budget);
      if (!code)
        return tl::unexpected(code.error());
      decoded_bytes = std::move(*code);
      bytes = decoded_bytes;
    }
    if (bytes.size() > budget)
      return over_budget(f);
    budget -= bytes.size();
    if (auto written = write_file(dir / *rel, bytes, f.executable.value_or(false)); !written)
      return written;
  }
  return {};
}

// A name a client sent, checked: BadRequest when it is not a name.
CallResult<void> checked_name(const std::string &name) {
  if (auto named = check_name("the application", name); !named)
    return control::call_error(Status::BadRequest, named.error());
  return {};
}

// A problem found in a staged install, with the staging folder taken out of its paths: they then
// read as the client's, relative to the SDR root its files came from, rather than as a folder
// that is gone once the install ends.
std::string as_client_paths(std::string text, const fs::path &staged) {
  const std::string prefix = (staged / "").string();
  for (auto at = text.find(prefix); at != std::string::npos; at = text.find(prefix, at))
    text.erase(at, prefix.size());
  return text;
}

// The application `request` carries, its files written into `dir` and loaded from there; the
// SAD's path and the name are checked first. `sad`: the SAD's path inside `dir`.
CallResult<profile::ResolvedApplication>
write_and_load(const fs::path &dir, const InstallRequest &request, fs::path &sad) {
  auto relative = safe_relative(request.sad);
  if (!relative)
    return control::call_error(
        Status::BadRequest,
        fmt::format("the SAD's path \"{}\" is not inside an SDR root (an install names each "
                    "file relative to the SDR root it comes from)",
                    excerpt(request.sad, protocol::domain::kMaxInstallPath)));
  sad = *relative;
  if (request.name)
    if (auto named = checked_name(*request.name); !named)
      return tl::unexpected(named.error());
  if (auto written = write_files(dir, request.files); !written)
    return tl::unexpected(written.error());
  profile::ProfileLoader loader(dir);
  auto app = loader.load_application(dir / sad);
  if (!app)
    return control::call_error(Status::BadRequest, as_client_paths(app.error().to_string(), dir));
  return std::move(*app);
}

// An install for a launch (`rsca launch SAD`) of what no launch could run is refused before it
// replaces anything.
CallResult<void> launchable(const InstallRequest &request, const profile::ResolvedApplication &app,
                            const fs::path &staged) {
  if (!request.for_launch.value_or(false))
    return {};
  const auto refused = profile::launch_refusals(app);
  if (refused.empty())
    return {};
  std::vector<std::string> problems;
  for (const auto &r : refused)
    problems.push_back(as_client_paths(to_string(r), staged));
  return control::call_error(Status::BadRequest,
                             fmt::format("the application cannot be launched, nothing was "
                                         "installed:\n{}",
                                         fmt::join(problems, "\n")));
}

// The application's components then start from their runtime models, without reading XML; a
// component without one still starts, reading its profile (profile/runtime_model.hpp).
void write_runtime_models(const profile::ResolvedApplication &app) {
  for (const auto &[id, softpkg] : app.component_files)
    if (auto ok = profile::write_runtime_model(*softpkg); !ok)
      spdlog::warn("no runtime model for {}: {}", softpkg->spd_path.string(),
                   ok.error().to_string());
}

} // namespace

InstalledRepository::InstalledRepository(fs::path root, DomainStore &store)
    : root_(std::move(root)), store_(store) {}

std::optional<fs::path> InstalledRepository::folder_of(const InstalledRecord &record) const {
  if (!check_name("the installed application", record.name))
    return std::nullopt;
  const fs::path sad = fs::path(record.sad).lexically_normal();
  auto part = sad.begin();
  if (part == sad.end())
    return std::nullopt;
  if (*part == "applications" && ++part != sad.end() && *part == record.name)
    return applications_dir() / record.name;
  // An earlier version's layout: the application's folder at the repository's top.
  if (*sad.begin() == record.name && record.name != "applications")
    return root_ / record.name;
  return std::nullopt;
}

void InstalledRepository::load() {
  auto records = store_.installed();
  if (!records) {
    spdlog::error("installed applications not loaded: {}", records.error().to_string());
    return;
  }
  std::lock_guard lock(mutex_);
  for (const auto &r : *records) {
    auto folder = folder_of(r);
    if (!folder) {
      spdlog::warn("installed application \"{}\" skipped: its record ({}) does not place it in "
                   "a folder of its own inside the repository",
                   excerpt(r.name), excerpt(r.sad));
      continue;
    }
    profile::ProfileLoader loader(*folder);
    auto app = loader.load_application(root_ / r.sad);
    if (!app) {
      spdlog::warn("installed application {} no longer loads, skipped:\n{}", r.name,
                   app.error().to_string());
      continue;
    }
    write_runtime_models(*app); // anew: the files may have changed while the domain was down
    installed_[r.name] = {r.name, root_ / r.sad,
                          std::make_shared<const profile::ResolvedApplication>(std::move(*app))};
    folders_[r.name] = *folder;
  }
  spdlog::info("{} installed application(s) loaded", installed_.size());
}

CallResult<InstalledApplication> InstalledRepository::install(const InstallRequest &request) {
  // Written and loaded aside first: only an install that loads replaces anything.
  ScopedFolder staging(root_, staging_dir() / unique_name("install"));
  fs::path sad;
  auto app = write_and_load(staging.path(), request, sad);
  if (!app)
    return tl::unexpected(app.error());
  if (auto ok = launchable(request, *app, staging.path()); !ok)
    return tl::unexpected(ok.error());
  const std::string name =
      request.name.value_or(app->sad->name.empty() ? app->sad->id : app->sad->name);
  if (auto named = checked_name(name); !named)
    return tl::unexpected(named.error());
  std::lock_guard lock(mutex_);
  auto installed = replace(name, staging.path(), sad, request.for_launch.value_or(false));
  if (installed)
    staging.keep(); // it became the install
  return installed;
}

CallResult<std::shared_ptr<const profile::ResolvedApplication>>
InstalledRepository::read_aside(const InstallRequest &request) const {
  ScopedFolder staging(root_, staging_dir() / unique_name("read"));
  fs::path sad;
  auto app = write_and_load(staging.path(), request, sad);
  if (!app)
    return tl::unexpected(app.error());
  return std::make_shared<const profile::ResolvedApplication>(std::move(*app));
}

// Puts a staged install in the place of `name` (called with mutex_ held). What was installed
// under that name steps aside first and comes back if anything fails.
CallResult<InstalledApplication> InstalledRepository::replace(const std::string &name,
                                                              const fs::path &staged,
                                                              const fs::path &sad_in_install,
                                                              bool on_trial) {
  const fs::path target = applications_dir() / name;
  std::error_code ec;
  fs::create_directories(applications_dir(), ec);
  ScopedFolder previous(root_, {});
  const auto old = folders_.find(name);
  const fs::path old_folder = old != folders_.end() ? old->second : target;
  const auto old_install = installed_.find(name);
  std::optional<InstalledApplication> replaced;
  if (old_install != installed_.end())
    replaced = old_install->second;
  if (fs::exists(old_folder, ec)) {
    previous.reset(staging_dir() / unique_name("previous"));
    fs::rename(old_folder, previous.path(), ec);
    if (ec)
      previous.keep();
  }
  auto fail = [&](std::string why) -> CallResult<InstalledApplication> {
    remove_inside(root_, target);
    if (!previous.path().empty()) {
      std::error_code restore;
      fs::rename(previous.path(), old_folder, restore);
      if (!restore)
        previous.keep();
    }
    return control::call_error(Status::Failed, fmt::format("storing {}: {}", name, why));
  };
  if (ec)
    return fail(ec.message());
  fs::rename(staged, target, ec);
  if (ec)
    return fail(ec.message());
  profile::ProfileLoader loader(target);
  auto app = loader.load_application(target / sad_in_install);
  if (!app)
    return fail(app.error().to_string());
  const fs::path sad = target / sad_in_install;
  if (auto stored = store_.put_installed({name, sad.lexically_relative(root_).string()}); !stored)
    return fail(stored.error().to_string());
  write_runtime_models(*app);
  InstalledApplication installed{
      name, sad, std::make_shared<const profile::ResolvedApplication>(std::move(*app))};
  installed_[name] = installed;
  folders_[name] = target;
  if (!on_trial) {
    drop_trial(name); // final: what an earlier trial held goes
  } else if (!trials_.contains(name)) {
    trials_[name] = Trial{previous.path(), old_folder, std::move(replaced)};
    previous.keep(); // held until the launch ends
  } // else: the earlier trial holds the last installation not on trial; this one's goes
  return installed;
}

std::string InstalledRepository::settle(const std::string &name, bool launched) {
  std::lock_guard lock(mutex_);
  auto it = trials_.find(name);
  if (it == trials_.end())
    return {};
  Trial trial = std::move(it->second);
  trials_.erase(it);
  if (!launched)
    return restore(name, std::move(trial));
  if (!trial.held.empty())
    remove_inside(root_, trial.held);
  return {};
}

void InstalledRepository::drop_trial(const std::string &name) {
  auto it = trials_.find(name);
  if (it == trials_.end())
    return;
  if (!it->second.held.empty())
    remove_inside(root_, it->second.held);
  trials_.erase(it);
}

// Puts back what the install on trial replaced (called with mutex_ held), or removes the install
// when it replaced nothing.
std::string InstalledRepository::restore(const std::string &name, Trial trial) {
  if (const auto current = folders_.find(name); current != folders_.end())
    remove_inside(root_, current->second);
  installed_.erase(name);
  folders_.erase(name);
  std::error_code ec;
  if (!trial.held.empty() && trial.previous)
    fs::rename(trial.held, trial.folder, ec);
  const bool back = !trial.held.empty() && trial.previous && !ec;
  const auto stored =
      back ? store_.put_installed({name, trial.previous->sad.lexically_relative(root_).string()})
           : store_.remove_installed(name);
  if (!stored)
    spdlog::error("the record of installed application {} not updated: {}", name,
                  stored.error().to_string());
  if (back) {
    installed_[name] = std::move(*trial.previous);
    folders_[name] = trial.folder;
    spdlog::info("installed application {}: its launch failed, the installation it replaced is "
                 "back",
                 name);
    return fmt::format("the installation of {} it replaced is back", name);
  }
  if (!trial.held.empty()) {
    spdlog::error("installed application {}: the installation it replaced could not be put "
                  "back: {}",
                  name, ec.message());
    remove_inside(root_, trial.held);
    return fmt::format("{} is no longer installed: the installation it replaced could not be put "
                       "back ({})",
                       name, ec.message());
  }
  spdlog::info("installed application {}: its launch failed, uninstalled again", name);
  return fmt::format("{} is uninstalled again (this launch had installed it)", name);
}

CallResult<void> InstalledRepository::uninstall(const std::string &name) {
  if (auto named = checked_name(name); !named)
    return tl::unexpected(named.error());
  std::lock_guard lock(mutex_);
  auto it = installed_.find(name);
  if (it == installed_.end())
    return control::call_error(Status::NotFound,
                               fmt::format("no application {} is installed", name));
  // The record first: files removed under a record that stays would not load after a restart.
  if (auto forgotten = store_.remove_installed(name); !forgotten)
    return control::call_error(
        Status::Failed, fmt::format("uninstalling {}: {}", name, forgotten.error().to_string()));
  remove_inside(root_, folders_.at(name));
  installed_.erase(it);
  folders_.erase(name);
  drop_trial(name);
  return {};
}

std::optional<InstalledApplication> InstalledRepository::find(const std::string &name) const {
  std::lock_guard lock(mutex_);
  auto it = installed_.find(name);
  if (it == installed_.end())
    return std::nullopt;
  return it->second;
}

std::vector<InstalledApplication> InstalledRepository::list() const {
  std::lock_guard lock(mutex_);
  std::vector<InstalledApplication> out;
  for (const auto &[name, app] : installed_)
    out.push_back(app);
  return out;
}

} // namespace rsca::domain
