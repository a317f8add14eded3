// What the domain delivers of a code file: what runs, not what debugs. A 64-bit ELF file with
// debug sections (a RelWithDebInfo build's executables are 97% debug information) is delivered as
// a copy without them, made once per file stamp by binutils' `objcopy --strip-debug` (a child
// process, bounded in time) into <repository>/.delivered/<sha256>, named by its content; the full
// file is kept where gdb finds it by build id, <repository>/.build-id/xx/rest.debug (gdb -iex 'set
// debug-file-directory <repository>'). Any other file is delivered as it is, and so is one that
// objcopy cannot strip (the reason logged).
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>

namespace rsca::domain {

class DeliveredCode {
public:
  // Removes the copies an earlier domain left: nothing refers to them any more.
  explicit DeliveredCode(std::filesystem::path repository);

  // The file to deliver for `file`: itself, or its copy without debug sections.
  std::filesystem::path deliverable(const std::filesystem::path &file);
  // Removes a copy that is no longer served; a file outside the copies' folder stays.
  void forget(const std::filesystem::path &delivered) const;

  std::filesystem::path copies_dir() const { return repository_ / ".delivered"; }
  std::filesystem::path debug_dir() const { return repository_ / ".build-id"; }

private:
  void keep_debug_file(const std::filesystem::path &file, const std::string &build_id) const;

  std::filesystem::path repository_;
};

// What a node gets of a code file (rsca-domaind --delivery): Stripped, what runs, each piece
// compressed when the node asks (FileManager); AsIs, the file itself and uncompressed, debug
// information and all (for a node's host where gdb must find it, and to compare).
enum class CodeDelivery : std::uint8_t { Stripped, AsIs };

} // namespace rsca::domain
