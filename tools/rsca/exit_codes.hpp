// The CLI's exit codes, distinct so scripts can tell failures apart.
#pragma once

namespace rsca::cli {

enum ExitCode : int {
  kOk = 0,
  kInvalidProfile = 1, // a profile is malformed or inconsistent
  kUsage = 2,          // the command line itself is wrong
  kNotFound = 3,       // a path given on the command line does not exist
};

} // namespace rsca::cli
