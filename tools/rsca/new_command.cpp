// rsca new component NAME: a component's project to build outside rsca's tree against an
// installed rsca — its source, SPD, PRF and SCD, a SAD that runs it alone, and a CMakeLists that
// finds rsca with find_package and installs into an SDR root.
// rsca new device NAME: the same for a device — a library rsca-noded loads (node/device_export.hpp)
// with its SPD, PRF and SCD, and a DCD of a node that runs it.
// The files are templates compiled into the CLI (tools/rsca/templates), so the CLI and the SDK it
// belongs to never disagree.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <span>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tl/expected.hpp>

#include "commands.hpp"
#include "common/text.hpp"
#include "domain_client.hpp"
#include "exit_codes.hpp"

namespace rsca::cli {
namespace templates {
// Generated from templates/*.in by cmake/RscaEmbed.cmake.
std::string_view embedded_file(std::string_view name);
} // namespace templates

namespace {

namespace fs = std::filesystem;

// A template and where its text goes in the project, NAME standing for the component's name.
struct ProjectFile {
  std::string_view template_name;
  std::string_view path;
};

constexpr ProjectFile kComponentFiles[] = {
    {"component.CMakeLists.txt.in", "CMakeLists.txt"}, {"component.cpp.in", "src/NAME.cpp"},
    {"component.spd.xml.in", "NAME.spd.xml"},          {"component.prf.xml.in", "NAME.prf.xml"},
    {"component.scd.xml.in", "NAME.scd.xml"},          {"component.sad.xml.in", "NAME.sad.xml"},
};

constexpr ProjectFile kDeviceFiles[] = {
    {"device.CMakeLists.txt.in", "CMakeLists.txt"}, {"device.cpp.in", "src/NAME.cpp"},
    {"device.spd.xml.in", "NAME.spd.xml"},          {"device.prf.xml.in", "NAME.prf.xml"},
    {"device.scd.xml.in", "NAME.scd.xml"},          {"device.dcd.xml.in", "DeviceManager.dcd.xml"},
};

// What `rsca new` makes: its files, and what to do next ({0}: the project, {1}: the name).
// $SDRROOT is REDHAWK's variable, which rsca reads too: the hint says what it is.
struct ProjectKind {
  std::string_view kind;
  std::span<const ProjectFile> files;
  std::string_view next;
};

constexpr std::string_view kSdrRootHint =
    "(SDRROOT: your SDR root, the folder whose dom/ holds applications and components and whose "
    "dev/ holds devices and nodes, e.g. export SDRROOT=$HOME/sdr; `rsca validate .` reads the "
    "project's profiles in place, before any install)\n";

constexpr ProjectKind kComponent{"component", kComponentFiles,
                                 "next:\n  cd {0} && rsca validate .\n"
                                 "  cmake -B build && cmake --build build\n"
                                 "  cmake --install build --prefix \"$SDRROOT\"\n"
                                 "  rsca launch \"$SDRROOT/dom/waveforms/{1}/{1}.sad.xml\"\n"};

constexpr ProjectKind kDevice{
    "device", kDeviceFiles,
    "next:\n  cd {0} && rsca validate .\n"
    "  cmake -B build && cmake --build build\n"
    "  cmake --install build --prefix \"$SDRROOT\"\n"
    "  rsca domain up --node \"$SDRROOT/dev/nodes/{1}_node/DeviceManager.dcd.xml\"\n"
    "  rsca query {1}_node:{1}_1\n"};

// A random (version 4) UUID, for the SPD's and the SAD's DCE ids.
std::string random_uuid() {
  std::random_device device;
  std::uniform_int_distribution<unsigned> byte(0, 255);
  unsigned char b[16];
  for (auto &x : b)
    x = static_cast<unsigned char>(byte(device));
  b[6] = static_cast<unsigned char>((b[6] & 0x0FU) | 0x40U); // version 4
  b[8] = static_cast<unsigned char>((b[8] & 0x3FU) | 0x80U); // RFC 4122 variant
  return fmt::format("{:02x}{:02x}{:02x}{:02x}-{:02x}{:02x}-{:02x}{:02x}-{:02x}{:02x}-"
                     "{:02x}{:02x}{:02x}{:02x}{:02x}{:02x}",
                     b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7], b[8], b[9], b[10], b[11],
                     b[12], b[13], b[14], b[15]);
}

// Names that are identifiers yet would not build: C++'s keywords and alternative tokens, what the
// templates' own code calls by its short name, and targets CMake keeps for itself.
constexpr std::string_view kReservedNames[] = {"alignas",       "alignof",     "and",
                                               "and_eq",        "asm",         "auto",
                                               "bitand",        "bitor",       "bool",
                                               "break",         "case",        "catch",
                                               "char",          "char8_t",     "char16_t",
                                               "char32_t",      "class",       "compl",
                                               "concept",       "const",       "consteval",
                                               "constexpr",     "constinit",   "const_cast",
                                               "continue",      "co_await",    "co_return",
                                               "co_yield",      "decltype",    "default",
                                               "delete",        "do",          "double",
                                               "dynamic_cast",  "else",        "enum",
                                               "explicit",      "export",      "extern",
                                               "false",         "float",       "for",
                                               "friend",        "goto",        "if",
                                               "inline",        "int",         "long",
                                               "mutable",       "namespace",   "new",
                                               "noexcept",      "not",         "not_eq",
                                               "nullptr",       "operator",    "or",
                                               "or_eq",         "private",     "protected",
                                               "public",        "register",    "reinterpret_cast",
                                               "requires",      "return",      "short",
                                               "signed",        "sizeof",      "static",
                                               "static_assert", "static_cast", "struct",
                                               "switch",        "template",    "this",
                                               "thread_local",  "throw",       "true",
                                               "try",           "typedef",     "typeid",
                                               "typename",      "union",       "unsigned",
                                               "using",         "virtual",     "void",
                                               "volatile",      "wchar_t",     "while",
                                               "xor",           "xor_eq",      "rsca",
                                               "std",           "Clock",       "Component",
                                               "Context",       "Result",      "all",
                                               "clean",         "help",        "install",
                                               "package",       "test"};

// The name becomes a C++ class, file names and profile names: an identifier, of a sane length,
// that builds.
bool valid_name(const std::string &name) {
  static const std::regex identifier("[A-Za-z][A-Za-z0-9_]{0,63}");
  return std::regex_match(name, identifier) &&
         std::find(std::begin(kReservedNames), std::end(kReservedNames), name) ==
             std::end(kReservedNames);
}

bool write_file(const fs::path &path, std::string_view text) {
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  std::ofstream out(path, std::ios::binary);
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  return static_cast<bool>(out.flush());
}

// Writes the project in a hidden folder beside `target` and renames it into place, so that a
// failure leaves nothing half-written. Returns the project's files, or the reason it failed.
tl::expected<std::vector<fs::path>, std::string>
write_project(const ProjectKind &kind, const std::string &name, const fs::path &target) {
  // Its own staging folder: a concurrent `rsca new` of the same name keeps its own.
  const fs::path staging =
      target.parent_path() / fmt::format(".{}.rsca-new-{}", name, random_uuid());
  std::error_code ec;
  const std::string spd_id = random_uuid(), sad_id = random_uuid(), dcd_id = random_uuid();
  std::vector<fs::path> written;
  for (const auto &file : kind.files) {
    std::string text(templates::embedded_file(file.template_name));
    if (text.empty()) { // every template named above is embedded (tools/rsca/CMakeLists.txt)
      fs::remove_all(staging, ec);
      return tl::unexpected(fmt::format("no template {} in this rsca", file.template_name));
    }
    for (const auto &[from, to] : {std::pair<std::string_view, std::string_view>{"@NAME@", name},
                                   {"@SPD_ID@", spd_id},
                                   {"@SAD_ID@", sad_id},
                                   {"@DCD_ID@", dcd_id},
                                   {"@RSCA_VERSION@", RSCA_VERSION}})
      replace_all(text, from, to);
    std::string relative(file.path);
    replace_all(relative, "NAME", name);
    if (!write_file(staging / relative, text)) {
      fs::remove_all(staging, ec);
      return tl::unexpected(fmt::format("cannot write {}", (staging / relative).string()));
    }
    written.push_back(target / relative);
  }
  fs::rename(staging, target, ec);
  if (ec) {
    const std::string why = ec.message();
    fs::remove_all(staging, ec);
    return tl::unexpected(fmt::format("cannot create {}: {}", target.string(), why));
  }
  return written;
}

int new_project(const ProjectKind &kind, const std::string &name, const std::string &dir,
                const GlobalOptions &global) {
  if (!valid_name(name))
    return fail(global, fmt::format("new {}", kind.kind), kUsage,
                fmt::format("\"{}\" is not a name: a letter, then letters, digits or _ (at most "
                            "64), and not a C++ keyword nor a name the project's code or CMake "
                            "keeps for itself",
                            name));
  const fs::path target = fs::absolute(fs::path(dir) / name).lexically_normal();
  std::error_code ec;
  // A local file error, as a usage error is: the domain is not asked (it was exit code 5, the
  // domain's refusal).
  if (fs::exists(target, ec))
    return fail(global, fmt::format("new {}", kind.kind), kUsage,
                fmt::format("{} already exists; nothing written (give another NAME, or another "
                            "folder with -o/--out)",
                            target.string()));
  auto files = write_project(kind, name, target);
  if (!files)
    return fail(global, fmt::format("new {}", kind.kind), kFailed, files.error());
  if (global.json) {
    nlohmann::json out{{std::string(kind.kind), name}, {"project", target.string()}, {"files", {}}};
    for (const auto &f : *files)
      out["files"].push_back(f.string());
    fmt::print("{}\n", out.dump(2));
    return kOk;
  }
  fmt::print("created {}\n", target.string());
  for (const auto &f : *files)
    fmt::print("  {}\n", f.lexically_relative(target).string());
  fmt::print(fmt::runtime(kind.next), target.string(), name);
  fmt::print("{}", kSdrRootHint);
  return kOk;
}

void add_project_command(CLI::App &parent, const ProjectKind &kind, std::string description,
                         const GlobalOptions &global, int &exit_code) {
  auto *cmd = parent.add_subcommand(std::string(kind.kind), std::move(description));
  auto name = std::make_shared<std::string>();
  auto dir = std::make_shared<std::string>(".");
  cmd->add_option("name", *name, fmt::format("The {}'s name (a C++ identifier)", kind.kind))
      ->required();
  cmd->add_option("-o,--out,--dir", *dir, "Where the project's folder NAME is made")
      ->capture_default_str();
  cmd->callback([&kind, name, dir, &global, &exit_code] {
    exit_code = new_project(kind, *name, *dir, global);
  });
}

} // namespace

void add_new_command(CLI::App &app, const GlobalOptions &global, int &exit_code) {
  auto *cmd = app.add_subcommand("new", "Create a project for a new component or device, built "
                                        "against an installed rsca (find_package(rsca))");
  cmd->require_subcommand(1);
  add_project_command(
      *cmd, kComponent,
      "A component: its source, SPD, PRF, SCD, a SAD that runs it, and a CMakeLists", global,
      exit_code);
  add_project_command(*cmd, kDevice,
                      "A device: its source (a library rsca-noded loads), SPD, PRF, SCD, a DCD "
                      "of a node that runs it, and a CMakeLists",
                      global, exit_code);
}

} // namespace rsca::cli
