// An SDR root laid out as REDHAWK's: dom/ holds applications, components and libraries,
// dev/ holds devices and nodes. Profiles name files by absolute paths within those trees.
#pragma once

#include <filesystem>
#include <optional>
#include <string_view>

namespace rsca::profile {

enum class SdrTree : std::uint8_t { Dom, Dev };

class SdrRoot {
public:
  explicit SdrRoot(std::filesystem::path root);

  // The nearest ancestor of `file` whose dom/ or dev/ holds the file.
  static std::optional<SdrRoot> find_for(const std::filesystem::path &file);

  const std::filesystem::path &path() const { return root_; }

  // Where a name written in `referencing_file` points: "/x/y" under the given tree, "x/y"
  // relative to the referencing file's folder.
  std::filesystem::path resolve(std::string_view name,
                                const std::filesystem::path &referencing_file, SdrTree tree) const;

  // Whether `file` (normalised) lies inside this SDR root.
  bool contains(const std::filesystem::path &file) const;

private:
  std::filesystem::path root_;
};

} // namespace rsca::profile
