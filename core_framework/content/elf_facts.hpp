// What the domain needs to know of an executable or library before it delivers it: whether it is
// a 64-bit ELF file, whether it carries debug sections (.debug_*, .zdebug_*), and its GNU build id
// (what gdb finds its debug file by). Read from the section headers with <elf.h>, every offset and
// size checked against the file: a file that is not such an ELF file has no facts.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace rsca::content {

struct ElfFacts {
  std::vector<std::string> debug_sections; // their names, in the file's order
  std::optional<std::string> build_id;     // lowercase hex
};

std::optional<ElfFacts> elf_facts(const std::filesystem::path &file);

} // namespace rsca::content
