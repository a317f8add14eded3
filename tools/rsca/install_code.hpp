// What an install carries to the domain: the user's application read where its files stand (so
// that what is wrong in them is named in them, with line and column), made into the request, with
// the code that lies beside each SPD (profile::ResolvedApplication::code_files()) in base64,
// within kMaxInstallBytes in all.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "common/diagnostic.hpp"
#include "profile/profile_loader.hpp"
#include "protocol/domain_ops.hpp"

namespace rsca::cli {

struct UserApplication {
  profile::ResolvedApplication profile; // as read from the user's files
  protocol::domain::InstallRequest request;
  std::vector<Diagnostic> warnings; // what reading the files found, located in them
  std::filesystem::path root;       // the SDR root the files are named from
};

// `text` from the domain about the install `application` of `user`'s files, its paths into the
// domain's copy (REPOSITORY/applications/NAME/..., laid out as the SDR root they came from) made
// the user's files again.
std::string as_user_paths(const std::string &text, const std::string &application,
                          const UserApplication &user);

// The SDR root given with --sdrroot (absolute), and SDRROOT's (REDHAWK's variable, where a file
// with no SDR root above it finds one; profile::SdrRoot::locate has the order); nullopt: none.
std::optional<std::filesystem::path> given_sdrroot(const GlobalOptions &global);
std::optional<std::filesystem::path> environment_sdrroot();
// A loader of the user's profiles, each finding its SDR root so.
profile::ProfileLoader user_profile_loader(const GlobalOptions &global);

// Why `assign` (--assign COMPONENT=DEVICE) names a component `app` lacks, with the one meant if
// one is close; nullopt when each names one of its components.
std::optional<std::string> stray_assignment(const profile::ResolvedApplication &app,
                                            const std::map<std::string, std::string> &assign);

// The application of the SAD `sad` and the install request that carries it, named `name` (empty:
// the SAD's name); an error located in the user's files. Read here and carried to the domain, so
// that the CLI may run on another host than the domain daemon.
Expected<UserApplication> read_user_application(const std::filesystem::path &sad,
                                                const GlobalOptions &global,
                                                const std::string &name);

// A SAD file to launch, read and checked where it stands as the launch will check it
// (profile::launch_refusals), with the --assign COMPONENT=DEVICE of the launch: a SAD no launch
// could run, or an assignment of a component it lacks, is refused naming the user's file, line
// and column, before anything is sent. nullopt, and rc an exit code, when it is refused.
std::optional<UserApplication> launchable_file(const std::string &sad,
                                               const std::map<std::string, std::string> &assign,
                                               const GlobalOptions &global, int &rc);

// Adds the application's code files to `request`, named relative to the SDR root `root`; an
// error at the file that cannot be read or does not fit.
Expected<void> add_code_files(const profile::ResolvedApplication &app,
                              const std::filesystem::path &root,
                              protocol::domain::InstallRequest &request);

} // namespace rsca::cli
