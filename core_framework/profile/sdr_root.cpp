#include "profile/sdr_root.hpp"

namespace rsca::profile {

namespace fs = std::filesystem;

SdrRoot::SdrRoot(fs::path root) : root_(std::move(root)) {}

// The file must lie inside the root's dom/ or dev/: merely having such a folder beside it is not
// enough, or every file on Linux would find "/" (which holds /dev).
std::optional<SdrRoot> SdrRoot::find_for(const fs::path &file) {
  std::error_code ec;
  fs::path dir = fs::absolute(file, ec).lexically_normal().parent_path();
  for (; dir.has_relative_path(); dir = dir.parent_path()) {
    const auto name = dir.filename();
    if ((name == "dom" || name == "dev") && dir.parent_path().has_relative_path())
      return SdrRoot(dir.parent_path());
  }
  return std::nullopt;
}

std::optional<SdrRoot> SdrRoot::project_of(const fs::path &file) {
  std::error_code ec;
  const fs::path dir = fs::absolute(file, ec).lexically_normal().parent_path();
  if (ec || !fs::is_regular_file(dir / "CMakeLists.txt", ec))
    return std::nullopt;
  SdrRoot project(dir);
  project.project_ = true;
  return project;
}

std::optional<SdrRoot> SdrRoot::locate(const fs::path &file, const std::optional<fs::path> &given,
                                       const std::optional<fs::path> &fallback) {
  std::error_code ec;
  if (given)
    return SdrRoot(fs::absolute(*given, ec).lexically_normal());
  if (auto root = find_for(file))
    return root;
  if (auto project = project_of(file))
    return project;
  if (fallback && !fallback->empty())
    return SdrRoot(fs::absolute(*fallback, ec).lexically_normal());
  return std::nullopt;
}

bool SdrRoot::contains(const fs::path &file) const {
  const auto rel = file.lexically_normal().lexically_relative(root_);
  return !rel.empty() && *rel.begin() != "..";
}

fs::path SdrRoot::resolve(std::string_view name, const fs::path &referencing_file,
                          SdrTree tree) const {
  if (!name.empty() && name.front() == '/') {
    name.remove_prefix(1);
    if (project_) // the project's files lie side by side, its install lays them out
      return (root_ / fs::path(name).filename()).lexically_normal();
    return (root_ / (tree == SdrTree::Dom ? "dom" : "dev") / fs::path(name)).lexically_normal();
  }
  return (referencing_file.parent_path() / fs::path(name)).lexically_normal();
}

} // namespace rsca::profile
