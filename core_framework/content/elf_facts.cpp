#include "content/elf_facts.hpp"

#include <elf.h>

#include <cstring>
#include <fstream>

#include <fmt/format.h>

namespace rsca::content {

namespace {

constexpr std::uint64_t kMaxSections = 1U << 16U;
constexpr std::uint64_t kMaxNames = 1U << 20U; // the section names' table
constexpr std::uint64_t kMaxNote = 4096;       // the build id's note

// Reads `size` bytes at `offset` of a file of `file_size` bytes; nothing past its end.
bool read_at(std::ifstream &in, std::uint64_t file_size, std::uint64_t offset, std::uint64_t size,
             void *into) {
  if (offset > file_size || size > file_size - offset)
    return false;
  in.seekg(static_cast<std::streamoff>(offset));
  in.read(static_cast<char *>(into), static_cast<std::streamsize>(size));
  return static_cast<std::uint64_t>(in.gcount()) == size;
}

std::optional<std::string> build_id_of(const std::string &note) {
  std::size_t at = 0;
  while (at + sizeof(Elf64_Nhdr) <= note.size()) {
    Elf64_Nhdr header{};
    std::memcpy(&header, note.data() + at, sizeof header);
    at += sizeof header;
    const std::size_t name = (header.n_namesz + 3U) & ~std::size_t{3};
    const std::size_t desc = (header.n_descsz + 3U) & ~std::size_t{3};
    if (name > note.size() - at || desc > note.size() - at - name)
      return std::nullopt;
    if (header.n_type == NT_GNU_BUILD_ID && header.n_namesz == 4 &&
        note.compare(at, 4, std::string("GNU\0", 4)) == 0 && header.n_descsz > 0) {
      std::string hex;
      for (std::size_t i = 0; i < header.n_descsz; ++i)
        hex += fmt::format("{:02x}", static_cast<unsigned char>(note[at + name + i]));
      return hex;
    }
    at += name + desc;
  }
  return std::nullopt;
}

} // namespace

std::optional<ElfFacts> elf_facts(const std::filesystem::path &file) {
  std::error_code ec;
  const std::uint64_t file_size = std::filesystem::file_size(file, ec);
  std::ifstream in(file, std::ios::binary);
  Elf64_Ehdr header{};
  if (ec || !in || !read_at(in, file_size, 0, sizeof header, &header) ||
      std::memcmp(header.e_ident, ELFMAG, SELFMAG) != 0 || header.e_ident[EI_CLASS] != ELFCLASS64 ||
      header.e_ident[EI_DATA] != ELFDATA2LSB || header.e_shentsize != sizeof(Elf64_Shdr) ||
      header.e_shnum == 0 || header.e_shnum > kMaxSections || header.e_shstrndx >= header.e_shnum)
    return std::nullopt;
  std::vector<Elf64_Shdr> sections(header.e_shnum);
  if (!read_at(in, file_size, header.e_shoff, sections.size() * sizeof(Elf64_Shdr),
               sections.data()))
    return std::nullopt;
  const auto &names_header = sections[header.e_shstrndx];
  if (names_header.sh_size > kMaxNames)
    return std::nullopt;
  std::string names(names_header.sh_size, '\0');
  if (!read_at(in, file_size, names_header.sh_offset, names.size(), names.data()))
    return std::nullopt;
  ElfFacts facts;
  for (const auto &section : sections) {
    if (section.sh_name >= names.size())
      return std::nullopt;
    const std::string name(names.c_str() + section.sh_name);
    if (name.starts_with(".debug_") || name.starts_with(".zdebug_"))
      facts.debug_sections.push_back(name);
    if (name == ".note.gnu.build-id" && section.sh_type == SHT_NOTE &&
        section.sh_size <= kMaxNote) {
      std::string note(section.sh_size, '\0');
      if (read_at(in, file_size, section.sh_offset, note.size(), note.data()))
        facts.build_id = build_id_of(note);
    }
  }
  return facts;
}

} // namespace rsca::content
