#include "install_code.hpp"

#include <algorithm>
#include <fstream>
#include <string>

#include <fmt/format.h>

#include "content/base64.hpp"

namespace rsca::cli {

namespace fs = std::filesystem;

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

} // namespace rsca::cli
