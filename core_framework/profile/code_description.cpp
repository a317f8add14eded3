#include "profile/code_description.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace rsca::profile {
namespace {

using Json = nlohmann::json;

// Bounds on a file read from a user's folder: far above any component's declarations.
constexpr std::uintmax_t kMaxFileBytes = 1U << 20U;
constexpr std::size_t kMaxEntries = 4096;
constexpr std::size_t kMaxName = 256;

// A name the file gives, checked: a string of bounded size.
std::string name_in(const Json &value, const char *what) {
  if (!value.is_string() || value.get_ref<const std::string &>().size() > kMaxName)
    throw std::invalid_argument(
        fmt::format("{} is not a name of at most {} bytes", what, kMaxName));
  return value.get<std::string>();
}

const Json &list_in(const Json &document, const char *key) {
  const auto it = document.find(key);
  if (it == document.end() || !it->is_array() || it->size() > kMaxEntries)
    throw std::invalid_argument(
        fmt::format("\"{}\" is not a list of at most {} entries", key, kMaxEntries));
  return *it;
}

CodeDescription parse(const Json &document) {
  if (!document.is_object() || document.value("version", 0) != kCodeDescriptionVersion)
    throw std::invalid_argument(fmt::format(
        "not a code description of version {} (written by another rsca: build the component "
        "again)",
        kCodeDescriptionVersion));
  CodeDescription out;
  for (const auto &port : list_in(document, "ports")) {
    if (!port.is_object())
      throw std::invalid_argument("a port is not an object");
    const std::string direction = name_in(port.value("direction", Json()), "a port's direction");
    if (direction != "uses" && direction != "provides")
      throw std::invalid_argument(
          fmt::format("port direction \"{}\" is neither uses nor provides", direction));
    out.ports.push_back({name_in(port.value("name", Json()), "a port's name"),
                         direction == "uses" ? PortDirection::Uses : PortDirection::Provides,
                         port.value("resource", false)});
  }
  for (const auto &id : list_in(document, "properties"))
    out.properties.push_back(name_in(id, "a property id"));
  return out;
}

template <typename Defines>
std::vector<std::string> misfits(const CodeDescription &code, const SoftwareComponent *scd,
                                 Defines defines) {
  std::vector<std::string> out;
  for (const auto &port : code.ports) {
    const auto direction = port.resource ? PortDirection::Uses : port.direction;
    if (scd != nullptr && scd->find_port(port.name, direction) != nullptr)
      continue;
    out.push_back(fmt::format("the component has {} port \"{}\", which its SCD does not declare",
                              to_string(direction), port.name));
  }
  for (const auto &id : code.properties)
    if (!defines(id))
      out.push_back(fmt::format("property \"{}\" is bound, but the PRF does not define it", id));
  return out;
}

void check_package(const ResolvedSoftPkg &pkg, std::vector<Diagnostic> &out) {
  for (const auto &impl : pkg.implementations) {
    const auto code = pkg.spd_path.parent_path() / impl.implementation->code.file.name;
    const auto described = code_description_path(code);
    std::error_code ec;
    if (impl.implementation->code.file.name.empty() ||
        !std::filesystem::is_regular_file(code, ec) ||
        !std::filesystem::is_regular_file(described, ec))
      continue;
    auto description = read_code_description(described);
    if (!description) {
      for (auto d : description.error().diagnostics())
        out.push_back(std::move(d));
      continue;
    }
    auto defines = [&pkg](const std::string &id) { return pkg.find_property(id) != nullptr; };
    for (auto &why : misfits(*description, pkg.scd.get(), defines))
      out.push_back({{pkg.spd_path.string(), 0, 0},
                     "code",
                     fmt::format("its code {} does not fit its profiles: {}", code.string(), why),
                     Severity::Error});
  }
}

} // namespace

std::string to_json_text(const CodeDescription &description) {
  Json ports = Json::array();
  for (const auto &p : description.ports)
    ports.push_back({{"name", p.name},
                     {"direction", std::string(to_string(p.direction))},
                     {"resource", p.resource}});
  return Json{{"version", kCodeDescriptionVersion},
              {"ports", std::move(ports)},
              {"properties", description.properties}}
      .dump(2);
}

std::filesystem::path code_description_path(const std::filesystem::path &code) {
  return std::filesystem::path(code.string() + std::string(kCodeDescriptionSuffix));
}

Expected<CodeDescription> read_code_description(const std::filesystem::path &file) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(file, ec);
  if (ec)
    return make_error({file.string(), 0, 0}, "code-description", ec.message());
  if (size > kMaxFileBytes)
    return make_error({file.string(), 0, 0}, "code-description",
                      fmt::format("larger than {} bytes: not a code description", kMaxFileBytes));
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  try {
    return parse(Json::parse(text.str()));
  } catch (const std::exception &e) {
    return make_error({file.string(), 0, 0}, "code-description", e.what());
  }
}

std::vector<std::string> code_misfits(const CodeDescription &code, const SoftwareComponent *scd,
                                      const std::vector<PropertyDefinition> &definitions) {
  return misfits(code, scd, [&definitions](const std::string &id) {
    return std::any_of(definitions.begin(), definitions.end(),
                       [&](const auto &d) { return common_of(d).id == id; });
  });
}

std::vector<Diagnostic> code_refusals(const ResolvedSoftPkg &pkg) {
  std::vector<Diagnostic> out;
  check_package(pkg, out);
  return out;
}

std::vector<Diagnostic> code_refusals(const ResolvedApplication &app) {
  std::vector<Diagnostic> out;
  for (const auto &[id, pkg] : app.component_files)
    check_package(*pkg, out);
  return out;
}

} // namespace rsca::profile
