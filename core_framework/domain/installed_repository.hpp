// InstalledRepository: the applications installed in the domain. Each one's profiles are copied
// into a folder of its own inside the domain's repository (applications/NAME), loaded from there,
// and recorded in the domain's store, so that a restarted domain daemon has them again.
//
// Nothing a client sends can make the repository act outside itself: a name is checked as a name
// (common/names.hpp) before it touches the file system, a file's path must be relative and stay
// inside the install, and every folder the repository removes or replaces is checked to lie inside
// it. An install is staged in a folder of its own and takes the application's place only once it
// loads (and, for a launch, only once nothing in it would make the launch refuse it); one that
// fails at any point leaves the repository as it was (no staging folder, the previous install of
// the same name intact).
//
// An install for a launch (`rsca launch SAD`) is on trial until that launch ends: what it replaced
// is held aside, and comes back if the launch fails (settle), so that a SAD that passes the checks
// but does not launch never replaces a good installation. Held is the last installation that was
// not on trial; any install not for a launch ends a trial (it is final).
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "control/endpoint.hpp"
#include "domain/domain_store.hpp"
#include "profile/profile_loader.hpp"
#include "protocol/domain_ops.hpp"

namespace rsca::domain {

struct InstalledApplication {
  std::string name;
  std::filesystem::path sad;
  std::shared_ptr<const profile::ResolvedApplication> profile;
};

// What to install: the SAD and every file it needs, as `domain.install` carries them.
using InstallFile = protocol::domain::InstallFile;
using InstallRequest = protocol::domain::InstallRequest;

class InstalledRepository {
public:
  InstalledRepository(std::filesystem::path root, DomainStore &store);

  // Loads what the store says is installed; an application that no longer loads is skipped
  // with a warning.
  void load();
  control::CallResult<InstalledApplication> install(const InstallRequest &request);
  // The application `request` carries, read in a staging folder that is removed again: what it
  // would install, installing nothing (`rsca plan SAD`).
  control::CallResult<std::shared_ptr<const profile::ResolvedApplication>>
  read_aside(const InstallRequest &request) const;
  control::CallResult<void> uninstall(const std::string &name);
  // Ends the trial of `name`'s install (nothing when it is on none): kept when its launch
  // `launched`, else replaced again by what it replaced, or removed when it replaced nothing.
  // What was done, for the launch's error ("" when nothing was).
  std::string settle(const std::string &name, bool launched);
  std::optional<InstalledApplication> find(const std::string &name) const;
  std::vector<InstalledApplication> list() const;

private:
  std::filesystem::path applications_dir() const { return root_ / "applications"; }
  std::filesystem::path staging_dir() const { return root_ / ".staging"; }
  // The folder an installed application's record places it in: applications/NAME, or NAME for
  // what an earlier version installed; nothing when the record points elsewhere.
  std::optional<std::filesystem::path> folder_of(const InstalledRecord &record) const;
  control::CallResult<std::filesystem::path> stage(const InstallRequest &request) const;
  control::CallResult<InstalledApplication> replace(const std::string &name,
                                                    const std::filesystem::path &staged,
                                                    const std::filesystem::path &sad_in_install,
                                                    bool on_trial);
  // What an install on trial replaced: its files (moved aside to `held`) and where they were.
  struct Trial {
    std::filesystem::path held; // empty: it replaced nothing
    std::filesystem::path folder;
    std::optional<InstalledApplication> previous;
  };
  void begin_trial(const std::string &name, std::filesystem::path held,
                   const std::filesystem::path &folder);
  void drop_trial(const std::string &name);
  std::string restore(const std::string &name, Trial trial);

  std::filesystem::path root_;
  DomainStore &store_;
  mutable std::mutex mutex_;
  std::map<std::string, InstalledApplication> installed_;
  std::map<std::string, std::filesystem::path> folders_; // where each one's files are
  std::map<std::string, Trial> trials_;                  // installs for a launch not yet ended
};

} // namespace rsca::domain
