#include "common/install_layout.hpp"

#include "common/install_dirs.hpp"
#include "common/own_folder.hpp"

namespace rsca::layout {

namespace fs = std::filesystem;

namespace {

bool is_folder(const fs::path &path) {
  std::error_code ec;
  return fs::is_directory(path, ec);
}

} // namespace

// The installed tree's folders when this program is installed, else the build tree's: an
// installed program never looks in bin/../lib, which is the system's /usr/lib.
std::vector<fs::path> library_folders() {
  const fs::path bin = own_folder();
  if (bin.empty())
    return {};
  if (const auto installed = (bin / installed::kLibFromBin).lexically_normal();
      is_folder(installed))
    return {installed};
  return {(bin / "../lib").lexically_normal()};
}

std::vector<fs::path> component_folders() {
  const fs::path bin = own_folder();
  if (bin.empty())
    return {};
  std::vector<fs::path> out{bin}; // rsca's own programs (the component host)
  if (const auto libexec = (bin / installed::kLibexecFromBin).lexically_normal();
      is_folder(libexec))
    out.push_back(libexec);
  for (auto &folder : library_folders())
    out.push_back(std::move(folder));
  return out;
}

fs::path resolve_code(const fs::path &file, const fs::path &spd,
                      const std::vector<fs::path> &folders) {
  const fs::path named = file.is_absolute() ? file : spd.parent_path() / file;
  std::error_code ec;
  if (fs::exists(named, ec))
    return named;
  for (const auto &folder : folders)
    if (fs::exists(folder / file.filename(), ec))
      return folder / file.filename();
  return named;
}

fs::path default_sdrroot() {
  const fs::path bin = own_folder();
  if (bin.empty())
    return {};
  for (const fs::path &candidate : {bin / installed::kProfilesFromBin, bin / "../../profiles"})
    if (is_folder(candidate))
      return candidate.lexically_normal();
  return {};
}

} // namespace rsca::layout
