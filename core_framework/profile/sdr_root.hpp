// An SDR root laid out as REDHAWK's: dom/ holds applications, components and libraries,
// dev/ holds devices and nodes. Profiles name files by absolute paths within those trees.
// A project `rsca new` made (its profiles side by side with a CMakeLists.txt, before its
// install lays them out in an SDR root) is read as a root of its own: an absolute name there
// stands for the project's file of that file name, where its install takes it from.
#pragma once

#include <filesystem>
#include <optional>
#include <string_view>

namespace rsca::profile {

enum class SdrTree : std::uint8_t { Dom, Dev };

// Why a file has no SDR root, and how to give it one (SdrRoot::locate's order).
inline constexpr std::string_view kNoSdrRoot =
    "no SDR root found: no --sdrroot was given, no folder above this file holds it in dom/ or "
    "dev/, no CMakeLists.txt lies beside it (a project `rsca new` made), and SDRROOT is not "
    "set; give --sdrroot DIR, or set SDRROOT=DIR, DIR being the SDR root whose dom/ and dev/ "
    "hold the files the profile names";

class SdrRoot {
public:
  explicit SdrRoot(std::filesystem::path root);

  // The nearest ancestor of `file` whose dom/ or dev/ holds the file.
  static std::optional<SdrRoot> find_for(const std::filesystem::path &file);
  // The SDR root of `file`, in this order: `given` (--sdrroot), the nearest ancestor whose dom/
  // or dev/ holds it, the project folder holding it (a CMakeLists.txt beside it: before SDRROOT,
  // which a new project's profiles are not installed in yet), `fallback` (the SDRROOT
  // environment variable). nullopt: none of them.
  static std::optional<SdrRoot> locate(const std::filesystem::path &file,
                                       const std::optional<std::filesystem::path> &given,
                                       const std::optional<std::filesystem::path> &fallback);
  // The project folder holding `file`, read as an SDR root; nullopt when its folder is none.
  static std::optional<SdrRoot> project_of(const std::filesystem::path &file);

  const std::filesystem::path &path() const { return root_; }
  bool is_project() const { return project_; }

  // Where a name written in `referencing_file` points: "/x/y" under the given tree, "x/y"
  // relative to the referencing file's folder.
  std::filesystem::path resolve(std::string_view name,
                                const std::filesystem::path &referencing_file, SdrTree tree) const;

  // Whether `file` (normalised) lies inside this SDR root.
  bool contains(const std::filesystem::path &file) const;

private:
  std::filesystem::path root_;
  bool project_ = false;
};

} // namespace rsca::profile
