// The code an install carries to the domain with the profiles: what lies beside each SPD
// (profile::ResolvedApplication::code_files()), in base64, within kMaxInstallBytes in all.
#pragma once

#include <filesystem>

#include "common/diagnostic.hpp"
#include "profile/profile_loader.hpp"
#include "protocol/domain_ops.hpp"

namespace rsca::cli {

// Adds the application's code files to `request`, named relative to the SDR root `root`; an
// error at the file that cannot be read or does not fit.
Expected<void> add_code_files(const profile::ResolvedApplication &app,
                              const std::filesystem::path &root,
                              protocol::domain::InstallRequest &request);

} // namespace rsca::cli
