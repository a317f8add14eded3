// The CLI's exit codes, distinct so scripts can tell failures apart.
#pragma once

namespace rsca::cli {

enum ExitCode : int {
  kOk = 0,
  kInvalidProfile = 1, // a profile is malformed or inconsistent, or a request was malformed
  kUsage = 2,          // the command line itself is wrong
  kNotFound = 3,       // a path, application, component or node that does not exist
  kUnreachable = 4,    // no domain daemon answered in time
  kRejected = 5,       // the domain refused (admission control, conflicting state)
  kFailed = 6,         // the operation was tried and failed (e.g. a launch, rolled back)
};

// The code's name, as a JSON error's "status" gives it.
constexpr const char *exit_name(int code) {
  constexpr const char *names[] = {"ok",          "invalid",  "usage", "not found",
                                   "unreachable", "rejected", "failed"};
  return code >= 0 && code <= kFailed ? names[code] : "failed";
}

} // namespace rsca::cli
