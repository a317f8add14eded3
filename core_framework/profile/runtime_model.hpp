// A component's runtime model: what a component process needs of its software package (the
// property definitions of its PRFs, the ports of its SCD) as JSON. The domain writes it next to
// each SPD it installs, so that a component process need not load the XML reader and parse its
// profile: that took about half of what a component process spends starting (docs/
// architecture.md, "Runtime models"). The model lists the files it came from with their
// modification times and sizes as they were before the domain read them (an edit racing the read
// makes the model stale, never wrongly current); one written for another SPD or that no longer
// matches them is not used, and the profile is read from its XML instead.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "common/diagnostic.hpp"
#include "profile/profile_loader.hpp"

namespace rsca::profile {

// Where the runtime model of the SPD `spd_file` lives: beside it.
std::filesystem::path runtime_model_path(const std::filesystem::path &spd_file);

nlohmann::json to_runtime_model(const ResolvedSoftPkg &softpkg);
// The software package `model` describes, as read from `spd_file`: its SPD-level PRF, one
// implementation per implementation-specific PRF, its SCD; no SPD model (`spd` is null).
Expected<std::shared_ptr<const ResolvedSoftPkg>>
from_runtime_model(const nlohmann::json &model, const std::filesystem::path &spd_file);

// Writes the runtime model beside the SPD `softpkg` was read from (atomically: a component
// starting meanwhile reads the old model or the new one, never half of one).
Expected<void> write_runtime_model(const ResolvedSoftPkg &softpkg);

// Whether `file` is named as a runtime model is.
bool is_runtime_model_path(const std::filesystem::path &file);

// Makes the model at `root`/`model_file`, a copy of one the domain wrote under `origin`, the model
// of the copies of its sources under `root`: each source under `origin` is named by its path
// relative to `root` (as a process started in `root` is given its SPD) and stamped as the copy is
// now. A node does it for the packages in its cache (node/package_cache.hpp), whose files never
// change once there. The file is replaced, not rewritten: another link to it keeps its content.
Expected<void> relocate_runtime_model(const std::filesystem::path &root,
                                      const std::filesystem::path &model_file,
                                      const std::string &origin);

// The software package of `spd_file` from its runtime model; an error says why there is none
// to use (missing, unreadable, or older than a file it came from).
Expected<std::shared_ptr<const ResolvedSoftPkg>>
read_runtime_model(const std::filesystem::path &spd_file);

// How a component process gets its profiles: from the runtime model when there is one to use,
// else from the XML (a component started by hand on a profile the domain did not install). Each
// SPD is read once, so that a component host with many instances of one component reads it once.
class ComponentProfileLoader {
public:
  Expected<std::shared_ptr<const ResolvedSoftPkg>> load(const std::filesystem::path &spd_file);

  // Why the last profile read from its XML had no runtime model to use; empty when it had one.
  const std::string &fallback_reason() const { return fallback_reason_; }

private:
  std::map<std::filesystem::path, std::shared_ptr<const ResolvedSoftPkg>> loaded_;
  std::optional<ProfileLoader> xml_; // made only when a profile has to be read from its XML
  std::string fallback_reason_;
};

} // namespace rsca::profile
