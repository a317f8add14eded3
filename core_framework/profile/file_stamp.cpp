#include "profile/file_stamp.hpp"

#include <system_error>

namespace rsca::profile {

std::optional<FileStamp> stamp_of(const std::filesystem::path &file) {
  std::error_code ec;
  const auto modified = std::filesystem::last_write_time(file, ec);
  if (ec)
    return std::nullopt;
  const auto size = std::filesystem::file_size(file, ec);
  if (ec)
    return std::nullopt;
  return FileStamp{static_cast<std::int64_t>(modified.time_since_epoch().count()), size};
}

} // namespace rsca::profile
