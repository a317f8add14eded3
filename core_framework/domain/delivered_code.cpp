#include "domain/delivered_code.hpp"

#include <unistd.h>

#include <atomic>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "content/elf_facts.hpp"
#include "content/sha256.hpp"
#include "process/run_program.hpp"

namespace rsca::domain {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

namespace {

// objcopy strips a 63 MB executable in about 60 ms: past this it is stuck.
constexpr auto kStripTimeout = 30s;

std::atomic<std::uint64_t> temporaries{0}; // for their names

bool lies_in(const fs::path &dir, const fs::path &file) {
  const fs::path rel = file.lexically_normal().lexically_relative(dir.lexically_normal());
  return !rel.empty() && *rel.begin() != ".." && rel != ".";
}

} // namespace

DeliveredCode::DeliveredCode(fs::path repository) : repository_(std::move(repository)) {
  std::error_code ec;
  fs::remove_all(copies_dir(), ec);
}

fs::path DeliveredCode::deliverable(const fs::path &file) {
  const auto facts = content::elf_facts(file);
  if (!facts || facts->debug_sections.empty())
    return file;
  static const auto objcopy = process::find_program("objcopy");
  if (!objcopy) {
    spdlog::warn("{}: delivered with its debug information: no objcopy in PATH (binutils)",
                 file.string());
    return file;
  }
  std::error_code ec;
  fs::create_directories(copies_dir(), ec);
  const fs::path temporary = copies_dir() / fmt::format(".strip.{}.{}", ::getpid(), ++temporaries);
  auto stripped = process::run_to_end(
      {.program = *objcopy, .args = {"--strip-debug", file.string(), temporary.string()}},
      kStripTimeout);
  if (!stripped) {
    fs::remove(temporary, ec);
    spdlog::warn("{}: delivered with its debug information: {}", file.string(), stripped.error());
    return file;
  }
  auto sha256 = content::sha256_of_file(temporary);
  if (!sha256) {
    fs::remove(temporary, ec);
    spdlog::warn("{}: delivered with its debug information: {}", file.string(),
                 sha256.error().to_string());
    return file;
  }
  // Named by its content: two launches that strip one file at once make one copy.
  const fs::path copy = copies_dir() / *sha256;
  fs::rename(temporary, copy, ec);
  if (ec) {
    fs::remove(temporary, ec);
    return file;
  }
  if (facts->build_id)
    keep_debug_file(file, *facts->build_id);
  spdlog::info("{}: delivered without its {} debug sections, as {} ({} bytes of {})", file.string(),
               facts->debug_sections.size(), copy.string(), fs::file_size(copy, ec),
               fs::file_size(file, ec));
  return copy;
}

// The full file, where gdb looks for a build id's debug information: a hard link when the
// repository is on the file's file system, else a copy.
void DeliveredCode::keep_debug_file(const fs::path &file, const std::string &build_id) const {
  if (build_id.size() < 3)
    return;
  const fs::path target =
      debug_dir() / build_id.substr(0, 2) / fmt::format("{}.debug", build_id.substr(2));
  std::error_code ec;
  if (fs::exists(target, ec))
    return; // the same build id: the same build
  fs::create_directories(target.parent_path(), ec);
  const fs::path temporary =
      fs::path(target).concat(fmt::format(".{}.{}.tmp", ::getpid(), ++temporaries));
  fs::create_hard_link(file, temporary, ec);
  if (ec) {
    ec.clear();
    fs::copy_file(file, temporary, fs::copy_options::overwrite_existing, ec);
  }
  if (!ec)
    fs::rename(temporary, target, ec);
  if (ec) {
    fs::remove(temporary, ec);
    spdlog::warn("{}: its debug information is not kept at {}: {}", file.string(), target.string(),
                 ec.message());
  }
}

void DeliveredCode::forget(const fs::path &delivered) const {
  if (!lies_in(copies_dir(), delivered))
    return;
  std::error_code ec;
  fs::remove(delivered, ec);
}

} // namespace rsca::domain
