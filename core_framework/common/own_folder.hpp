// The folder of this process's executable: rsca's programs find the others, and the components a
// development build keeps, beside themselves.
#pragma once

#include <filesystem>

namespace rsca {

inline std::filesystem::path own_folder() {
  std::error_code ec;
  auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path() : self.parent_path();
}

} // namespace rsca
