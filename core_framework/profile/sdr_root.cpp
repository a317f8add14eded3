#include "profile/sdr_root.hpp"

namespace rsca::profile {

namespace fs = std::filesystem;

SdrRoot::SdrRoot(fs::path root) : root_(std::move(root)) {}

std::optional<SdrRoot> SdrRoot::find_for(const fs::path &file) {
  std::error_code ec;
  fs::path dir = fs::absolute(file, ec).lexically_normal().parent_path();
  for (; !dir.empty(); dir = dir.parent_path()) {
    if (fs::is_directory(dir / "dom", ec) || fs::is_directory(dir / "dev", ec))
      return SdrRoot(dir);
    if (dir == dir.root_path())
      break;
  }
  return std::nullopt;
}

fs::path SdrRoot::resolve(std::string_view name, const fs::path &referencing_file,
                          SdrTree tree) const {
  if (!name.empty() && name.front() == '/') {
    name.remove_prefix(1);
    return (root_ / (tree == SdrTree::Dom ? "dom" : "dev") / fs::path(name)).lexically_normal();
  }
  return (referencing_file.parent_path() / fs::path(name)).lexically_normal();
}

} // namespace rsca::profile
