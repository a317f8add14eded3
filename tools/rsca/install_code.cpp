#include "install_code.hpp"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "allocator/planner.hpp"
#include "common/names.hpp"
#include "content/base64.hpp"
#include "domain_client.hpp"
#include "exit_codes.hpp"
#include "profile/application_checks.hpp"

namespace rsca::cli {

namespace fs = std::filesystem;

namespace {

std::string read_text(const fs::path &file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

// The SDR root of the user's SAD, as validate finds it (SdrRoot::locate); an error saying how to
// give one when there is none, or when it is a project not installed yet.
Expected<fs::path> sdrroot_of(const fs::path &sad, const GlobalOptions &global) {
  auto root = profile::SdrRoot::locate(sad, given_sdrroot(global), environment_sdrroot());
  if (!root)
    return make_error({sad.string(), 0, 0}, "sdrroot", std::string(profile::kNoSdrRoot));
  if (root->is_project())
    return make_error(
        {sad.string(), 0, 0}, "sdrroot",
        fmt::format("{} is a project `rsca new` made: `rsca validate` reads it in place, but a "
                    "launch needs it built and installed in an SDR root: cmake -B build && "
                    "cmake --build build && cmake --install build --prefix \"$SDRROOT\", then "
                    "rsca launch \"$SDRROOT/dom/waveforms/{}/{}\"",
                    root->path().string(), sad.stem().stem().string(), sad.filename().string()));
  return root->path();
}

// Where the SAD goes among the install's files: its place in the SDR root, or, for a SAD kept
// outside it (its names are absolute, so resolve in the root all the same), where an install
// into the root would put it.
std::string install_path_of_sad(const fs::path &sad, const fs::path &root) {
  if (profile::SdrRoot(root).contains(sad))
    return sad.lexically_relative(root).string();
  return (fs::path("dom/waveforms") / sad.stem().stem() / sad.filename()).string();
}

// Why `id` is no component of `sad`: its components, and the one meant if one is close.
std::string not_a_component(const profile::SoftwareAssembly &sad, const std::string &id) {
  std::vector<std::string> ids;
  for (const auto &placement : sad.placements)
    for (const auto &ci : placement.instantiations)
      ids.push_back(ci.id);
  const std::string close = closest_name(id, ids);
  return fmt::format("{} has no component \"{}\"{} (its components: {})", sad.name, id,
                     close.empty() ? "" : fmt::format(", did you mean \"{}\"?", close),
                     fmt::join(ids, ", "));
}

} // namespace

std::optional<std::string> stray_assignment(const profile::ResolvedApplication &app,
                                            const std::map<std::string, std::string> &assign) {
  auto stray = allocator::unknown_assignment(app, assign);
  if (!stray)
    return std::nullopt;
  return fmt::format("--assign {}: {}", *stray, not_a_component(*app.sad, *stray));
}

std::optional<fs::path> given_sdrroot(const GlobalOptions &global) {
  if (global.sdrroot.empty())
    return std::nullopt;
  return fs::absolute(global.sdrroot).lexically_normal();
}

std::optional<fs::path> environment_sdrroot() {
  const char *value = std::getenv("SDRROOT");
  if (value == nullptr || *value == '\0')
    return std::nullopt;
  return fs::absolute(value).lexically_normal();
}

profile::ProfileLoader user_profile_loader(const GlobalOptions &global) {
  return profile::ProfileLoader(given_sdrroot(global), environment_sdrroot());
}

Expected<UserApplication> read_user_application(const fs::path &sad, const GlobalOptions &global,
                                                const std::string &name) {
  auto root = sdrroot_of(sad, global);
  if (!root)
    return tl::unexpected(root.error());
  profile::ProfileLoader loader(*root);
  auto app = loader.load_application(sad);
  if (!app)
    return tl::unexpected(app.error());
  UserApplication user{std::move(*app), {}, {}, *root};
  user.warnings = user.profile.warnings;
  user.warnings.insert(user.warnings.end(), user.profile.tolerated.begin(),
                       user.profile.tolerated.end());
  auto &request = user.request;
  request.sad = install_path_of_sad(user.profile.sad_path, *root);
  for (const auto &f : user.profile.files())
    request.files.push_back(
        {f == user.profile.sad_path ? request.sad : fs::path(f).lexically_relative(*root).string(),
         read_text(f), std::nullopt, std::nullopt});
  if (auto carried = add_code_files(user.profile, *root, request); !carried)
    return tl::unexpected(carried.error());
  if (!name.empty())
    request.name = name;
  return user;
}

Expected<void> add_code_files(const profile::ResolvedApplication &app, const fs::path &root,
                              protocol::domain::InstallRequest &request) {
  using protocol::domain::kMaxInstallBytes;
  std::uint64_t bytes = 0;
  for (const auto &f : request.files)
    bytes += f.content.size();
  for (const auto &code : app.code_files()) {
    const std::uint64_t room = kMaxInstallBytes - std::min(bytes, kMaxInstallBytes);
    // Read up to one byte past the room: a file that grew since it was listed is still caught.
    std::ifstream in(code, std::ios::binary);
    std::string content(room + 1, '\0');
    in.read(content.data(), static_cast<std::streamsize>(content.size()));
    if (in.bad() || (!in && !in.eof()))
      return make_error({code.string(), 0, 0}, "install-read", "cannot read this code file");
    content.resize(static_cast<std::size_t>(in.gcount()));
    if (content.size() > room)
      return make_error({code.string(), 0, 0}, "install-size",
                        fmt::format("an install carries at most {} MiB in all and this code does "
                                    "not fit; put it in the domain's --exec-path instead",
                                    kMaxInstallBytes >> 20U));
    bytes += content.size();
    std::error_code ec;
    const auto perms = fs::status(code, ec).permissions();
    if (ec)
      return make_error({code.string(), 0, 0}, "install-read", ec.message());
    request.files.push_back({code.lexically_relative(root).string(),
                             content::base64_encode(content),
                             protocol::domain::FileEncoding::Base64,
                             (perms & fs::perms::owner_exec) != fs::perms::none});
  }
  return {};
}

std::optional<UserApplication> launchable_file(const std::string &sad,
                                               const std::map<std::string, std::string> &assign,
                                               const GlobalOptions &global, int &rc) {
  auto app = read_user_application(sad, global, "");
  if (!app) {
    rc = fail(global, "launch", kInvalidProfile, app.error().to_string());
    return std::nullopt;
  }
  if (auto stray = stray_assignment(app->profile, assign)) {
    rc = fail(global, "launch", kUsage, *stray + "; nothing was installed");
    return std::nullopt;
  }
  if (auto refused = profile::launch_refusals(app->profile); !refused.empty()) {
    std::string why = fmt::format("{} cannot be launched; nothing was installed:", sad);
    for (const auto &r : refused)
      why += "\n  " + to_string(r);
    rc = fail(global, "launch", kInvalidProfile, why);
    return std::nullopt;
  }
  app->request.for_launch = true; // the domain checks it again before it replaces anything
  return std::move(*app);
}

std::string as_user_paths(const std::string &text, const std::string &application,
                          const UserApplication &user) {
  const std::string marker = "/applications/" + application + "/";
  const std::string root = (user.root / "").string();
  std::string out;
  std::size_t done = 0;
  for (auto at = text.find(marker); at != std::string::npos; at = text.find(marker, done)) {
    // The path begins after the blank or quote before it.
    const auto blank = text.find_last_of(" \t\n\"'(", at);
    const std::size_t start = blank == std::string::npos ? done : std::max(blank + 1, done);
    out += text.substr(done, start - done) + root;
    done = at + marker.size();
  }
  return out + text.substr(done);
}

} // namespace rsca::cli
