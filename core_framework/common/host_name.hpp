// This machine's host name, as rsca's processes report and name themselves with it.
#pragma once

#include <unistd.h>

#include <string>

namespace rsca {

inline std::string host_name() {
  char host[256] = {}; // HOST_NAME_MAX is 64; gethostname cuts a longer one and may not end it
  ::gethostname(host, sizeof(host) - 1);
  return host;
}

} // namespace rsca
