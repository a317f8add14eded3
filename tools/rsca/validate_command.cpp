// rsca validate PATH...: reads, validates and resolves profiles; exit 0 only when all are valid.
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <variant>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "exit_codes.hpp"
#include "install_code.hpp"
#include "profile/profile_loader.hpp"

namespace rsca::cli {
namespace {

namespace fs = std::filesystem;
using profile::DescriptorType;

// Profiles in a folder are recognised by REDHAWK's file-name suffixes.
constexpr std::pair<std::string_view, DescriptorType> kSuffixes[] = {
    {".sad.xml", DescriptorType::SAD}, {".spd.xml", DescriptorType::SPD},
    {".scd.xml", DescriptorType::SCD}, {".prf.xml", DescriptorType::PRF},
    {".dcd.xml", DescriptorType::DCD}, {".dmd.xml", DescriptorType::DMD},
    {".dpd.xml", DescriptorType::DPD}};

std::optional<DescriptorType> type_from_name(const fs::path &file) {
  const std::string name = file.filename().string();
  for (const auto &[suffix, type] : kSuffixes)
    if (name.size() > suffix.size() && name.ends_with(suffix))
      return type;
  return std::nullopt;
}

// The files named: files as given, folders searched for profiles.
std::vector<fs::path> collect(const std::vector<std::string> &paths,
                              std::vector<std::string> &missing) {
  std::vector<fs::path> files;
  for (const auto &p : paths) {
    std::error_code ec;
    if (fs::is_regular_file(p, ec)) {
      files.emplace_back(p);
    } else if (fs::is_directory(p, ec)) {
      std::vector<fs::path> found;
      for (const auto &entry : fs::recursive_directory_iterator(p, ec))
        if (entry.is_regular_file() && type_from_name(entry.path()))
          found.push_back(entry.path());
      std::sort(found.begin(), found.end());
      files.insert(files.end(), found.begin(), found.end());
    } else {
      missing.push_back(p);
    }
  }
  return files;
}

struct Outcome {
  fs::path file;
  std::string type;
  Error error;                      // what makes the file invalid
  std::vector<Diagnostic> warnings; // what does not: a REDHAWK profile's, without --strict
  bool valid() const { return error.empty(); }
};

// A profile written for REDHAWK (its SCA DOCTYPE) is read as REDHAWK reads it, its findings
// warnings; one written for rsca, or any under --strict, has them as errors: what a launch
// refuses (profile::launch_refusals) and more.
bool strict_for(const profile::ValidatedDescriptor &validated, bool strict) {
  return strict || !std::visit([](const auto &d) { return d.redhawk; }, validated.descriptor);
}

nlohmann::json to_json(const Diagnostic &d) {
  return {{"file", d.where.file},
          {"line", d.where.line},
          {"column", d.where.column},
          {"severity", d.severity == Severity::Warning ? "warning" : "error"},
          {"rule", d.rule},
          {"message", d.message}};
}

void print_json(const std::vector<Outcome> &outcomes, const std::vector<std::string> &missing) {
  nlohmann::json files = nlohmann::json::array();
  std::size_t invalid = 0;
  for (const auto &o : outcomes) {
    nlohmann::json diagnostics = nlohmann::json::array();
    for (const auto &d : o.error.diagnostics())
      diagnostics.push_back(to_json(d));
    for (const auto &d : o.warnings)
      diagnostics.push_back(to_json(d));
    invalid += o.valid() ? 0 : 1;
    files.push_back({{"file", o.file.string()},
                     {"type", o.type},
                     {"valid", o.valid()},
                     {"diagnostics", diagnostics}});
  }
  nlohmann::json out{{"files", files},
                     {"valid", outcomes.size() - invalid},
                     {"invalid", invalid},
                     {"missing", missing}};
  std::cout << out.dump(2) << '\n';
}

void print_text(const std::vector<Outcome> &outcomes, const std::vector<std::string> &missing) {
  std::size_t invalid = 0;
  for (const auto &o : outcomes) {
    invalid += o.valid() ? 0 : 1;
    fmt::print("{:8} {:3}  {}\n", o.valid() ? "ok" : "INVALID", o.type, o.file.string());
    for (const auto &d : o.error.diagnostics())
      fmt::print("    {}\n", to_string(d));
    for (const auto &d : o.warnings)
      fmt::print("    {}\n", to_string(d));
  }
  for (const auto &m : missing)
    fmt::print(stderr, "rsca validate: {}: no such file or folder\n", m);
  fmt::print("{} profile{} checked: {} valid, {} invalid\n", outcomes.size(),
             outcomes.size() == 1 ? "" : "s", outcomes.size() - invalid, invalid);
}

int run(const std::vector<std::string> &paths, bool strict, const GlobalOptions &global) {
  std::vector<std::string> missing;
  auto files = collect(paths, missing);
  auto loader = user_profile_loader(global);
  std::vector<Outcome> outcomes;
  bool all_valid = true;
  for (const auto &file : files) {
    auto result = loader.validate(file);
    auto type = type_from_name(file);
    Outcome o{file, "?", result ? Error() : result.error(), {}};
    if (result) {
      o.type = profile::to_string(profile::type_of(result->descriptor));
      o.warnings = result->warnings;
      if (strict_for(*result, strict))
        for (auto &w : std::exchange(o.warnings, {}))
          o.error.add({w.where, w.rule, w.message, Severity::Error});
    } else if (type) {
      o.type = profile::to_string(*type);
    }
    all_valid = all_valid && o.valid();
    outcomes.push_back(std::move(o));
  }
  global.json ? print_json(outcomes, missing) : print_text(outcomes, missing);
  if (!missing.empty())
    return kNotFound;
  return all_valid ? kOk : kInvalidProfile;
}

} // namespace

void add_validate_command(CLI::App &app, const GlobalOptions &global, int &exit_code) {
  auto *cmd =
      app.add_subcommand("validate", "Validate profiles (files, or folders searched for "
                                     "*.sad.xml, *.spd.xml, ... ) and everything they reference");
  auto paths = std::make_shared<std::vector<std::string>>();
  auto strict = std::make_shared<bool>(false);
  cmd->add_option("paths", *paths, "Profile files or folders")->required();
  cmd->add_flag("--strict", *strict,
                "Treat warnings (e.g. a connection to a port the component lacks) as errors in "
                "REDHAWK's profiles too (those with the SCA DOCTYPE); a profile without it is "
                "written for rsca and always validated so");
  cmd->callback([paths, strict, &global, &exit_code] { exit_code = run(*paths, *strict, global); });
}

} // namespace rsca::cli
