// Who a started process runs as: a user's ids and groups, looked up once (the lookup reads
// /etc/passwd and /etc/group, or NSS, and allocates: never between fork and exec).
#pragma once

#include <string>
#include <vector>

#include <sys/types.h>

#include "common/diagnostic.hpp"

namespace rsca::process {

struct Credentials {
  std::string user; // the name it was looked up by, for messages
  uid_t uid = 0;
  gid_t gid = 0;
  std::vector<gid_t> groups{}; // supplementary groups: the user's, from the group database
};

// The user's credentials; an error (rule "user") when there is no such user on this host.
Expected<Credentials> credentials_of(const std::string &user);

// Whether this process may give a child another user's credentials (it is root).
bool may_change_user();

} // namespace rsca::process
