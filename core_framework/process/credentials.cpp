// process/credentials.hpp: getpwnam_r and getgrouplist, with buffers that grow as asked.
#include "process/credentials.hpp"

#include <cerrno>
#include <cstring>

#include <grp.h>
#include <pwd.h>
#include <unistd.h>

#include <fmt/format.h>

namespace rsca::process {
namespace {

tl::unexpected<Error> user_error(const std::string &user, std::string message) {
  return make_error({user, 0, 0}, "user", std::move(message));
}

// The user's supplementary groups, `gid` among them; just `gid` when the database says nothing.
std::vector<gid_t> groups_of(const std::string &user, gid_t gid) {
  int count = 16;
  std::vector<gid_t> groups(static_cast<std::size_t>(count));
  for (int tries = 0; tries < 8; ++tries) {
    int asked = count;
    if (::getgrouplist(user.c_str(), gid, groups.data(), &asked) >= 0) {
      groups.resize(static_cast<std::size_t>(asked));
      return groups;
    }
    count = asked > count ? asked : count * 2; // too small: `asked` says how many there are
    groups.resize(static_cast<std::size_t>(count));
  }
  return {gid};
}

} // namespace

Expected<Credentials> credentials_of(const std::string &user) {
  if (user.empty())
    return user_error(user, "no user named");
  std::vector<char> buffer(1024);
  passwd entry{};
  passwd *found = nullptr;
  int error = 0;
  while ((error = ::getpwnam_r(user.c_str(), &entry, buffer.data(), buffer.size(), &found)) ==
             ERANGE &&
         buffer.size() < (1U << 20U))
    buffer.resize(buffer.size() * 2);
  if (error != 0)
    return user_error(user,
                      fmt::format("cannot look user \"{}\" up: {}", user, std::strerror(error)));
  if (found == nullptr)
    return user_error(user, fmt::format("no user \"{}\" on this host", user));
  return Credentials{user, entry.pw_uid, entry.pw_gid, groups_of(user, entry.pw_gid)};
}

bool may_change_user() {
  return ::geteuid() == 0;
}

} // namespace rsca::process
