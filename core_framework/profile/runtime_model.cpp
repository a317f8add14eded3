#include "profile/runtime_model.hpp"

#include "profile/definition_json.hpp"

#include <fstream>
#include <system_error>
#include <unistd.h>

#include <fmt/format.h>

namespace rsca::profile {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

// Bumped whenever the layout changes: a model of another format is not used.
constexpr int kFormat = 2; // 2: sources stamped with modification time and size

// The JSON of a part a package may lack (null), and back.
template <typename T>
Json nullable_json(const std::shared_ptr<const T> &part) {
  return part ? to_json(*part) : Json();
}

template <typename T>
tl::expected<std::shared_ptr<const T>, std::string>
nullable_from(const Json &json, tl::expected<T, std::string> (*read)(const Json &)) {
  if (json.is_null())
    return nullptr;
  auto part = read(json);
  if (!part)
    return tl::unexpected(part.error());
  return std::make_shared<const T>(std::move(*part));
}

// --- the files a model came from ---

Json stamp_json(const std::optional<FileStamp> &stamp) {
  return stamp ? Json{stamp->modified_ns, stamp->size} : Json();
}

Json sources_json(const std::vector<SourceFile> &sources) {
  Json json = Json::array();
  for (const auto &source : sources)
    json.push_back({source.path, stamp_json(source.stamp)});
  return json;
}

std::vector<SourceFile> sources_from(const Json &json) {
  std::vector<SourceFile> sources;
  for (const auto &source : json) {
    const Json &stamp = source.at(1);
    sources.push_back(
        {source.at(0).get<std::string>(),
         stamp.is_null() ? std::nullopt
                         : std::optional<FileStamp>(FileStamp{stamp.at(0).get<std::int64_t>(),
                                                              stamp.at(1).get<std::uintmax_t>()})});
  }
  return sources;
}

// Empty when the model was written for `spd_file` and every file it came from is as it was
// before the domain read it; else what is not. A model copied along with its package still
// names the original's files.
std::string stale_because(const std::vector<SourceFile> &sources, const fs::path &spd_file) {
  if (sources.empty() || sources.front().path != spd_file.string())
    return "it was written for another SPD";
  for (const auto &source : sources)
    if (!source.stamp || stamp_of(source.path) != source.stamp)
      return fmt::format("{} changed since it was written", source.path);
  return {};
}

tl::unexpected<Error> model_error(const fs::path &file, std::string message) {
  return make_error({file.string(), 0, 0}, "runtime-model", std::move(message));
}

} // namespace

fs::path runtime_model_path(const fs::path &spd_file) {
  return fs::path(spd_file).concat(".model.json");
}

Json to_runtime_model(const ResolvedSoftPkg &softpkg) {
  Json implementations = Json::array();
  for (const auto &implementation : softpkg.implementations)
    if (implementation.properties)
      implementations.push_back(to_json(*implementation.properties));
  return {{"format", kFormat},
          {"sources", sources_json(softpkg.sources)},
          {"properties", nullable_json(softpkg.properties)},
          {"implementation_properties", implementations},
          {"scd", nullable_json(softpkg.scd)}};
}

Expected<std::shared_ptr<const ResolvedSoftPkg>> from_runtime_model(const Json &model,
                                                                    const fs::path &spd_file) {
  try {
    if (model.at("format").get<int>() != kFormat)
      return model_error(spd_file,
                         fmt::format("format {} is not {}", model.at("format").dump(), kFormat));
    auto softpkg = std::make_shared<ResolvedSoftPkg>();
    softpkg->spd_path = spd_file;
    softpkg->sources = sources_from(model.at("sources"));
    auto properties = nullable_from(model.at("properties"), &properties_from_json);
    if (!properties)
      return model_error(spd_file, properties.error());
    softpkg->properties = std::move(*properties);
    for (const auto &json : model.at("implementation_properties")) {
      auto prf = properties_from_json(json);
      if (!prf)
        return model_error(spd_file, prf.error());
      softpkg->implementations.push_back(
          {nullptr, std::make_shared<const Properties>(std::move(*prf)), {}});
    }
    auto scd = nullable_from(model.at("scd"), &software_component_from_json);
    if (!scd)
      return model_error(spd_file, scd.error());
    softpkg->scd = std::move(*scd);
    return softpkg;
  } catch (const std::exception &e) { // the model's own fields: nlohmann's errors
    return model_error(spd_file, e.what());
  }
}

// Writes `text` to `target` through a temporary beside it, renamed over it: a reader sees the old
// file or the new one, never half of one, and a file linked elsewhere keeps its content.
Expected<void> replace_file(const fs::path &target, const std::string &text) {
  const fs::path temporary = fs::path(target).concat(fmt::format(".{}.tmp", ::getpid()));
  {
    std::ofstream out(temporary, std::ios::trunc);
    out << text;
    out.close();
    if (!out) {
      std::error_code ignored;
      fs::remove(temporary, ignored);
      return model_error(target, fmt::format("cannot write {}", temporary.string()));
    }
  }
  std::error_code ec;
  fs::rename(temporary, target, ec);
  if (ec) {
    fs::remove(temporary, ec);
    return model_error(target, fmt::format("cannot store it: {}", ec.message()));
  }
  return {};
}

Expected<void> write_runtime_model(const ResolvedSoftPkg &softpkg) {
  const fs::path target = runtime_model_path(softpkg.spd_path);
  std::string text;
  try {
    text = to_runtime_model(softpkg).dump();
  } catch (const std::exception &e) { // e.g. a path that is not UTF-8
    return model_error(target, e.what());
  }
  return replace_file(target, text);
}

bool is_runtime_model_path(const fs::path &file) {
  const std::string name = file.filename().string();
  constexpr std::string_view suffix = ".model.json";
  return name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(),
                                                     suffix.data(), suffix.size()) == 0;
}

Expected<void> relocate_runtime_model(const fs::path &root, const fs::path &model_file,
                                      const std::string &origin) {
  const fs::path file = root / model_file;
  std::ifstream in(file);
  Json model = Json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (model.is_discarded() || !model.is_object() || !model.contains("sources") ||
      !model["sources"].is_array())
    return model_error(file, "it is not a runtime model");
  const std::string prefix = origin.empty() || origin.back() == '/' ? origin : origin + "/";
  std::vector<SourceFile> sources;
  try {
    sources = sources_from(model["sources"]);
  } catch (const std::exception &e) { // the model's own fields: nlohmann's errors
    return model_error(file, e.what());
  }
  for (auto &source : sources) {
    // A source outside the origin is not in the package: the model stays stale, and a
    // component that reads it falls back to its XML, as it would anywhere else.
    if (prefix.empty() || source.path.compare(0, prefix.size(), prefix) != 0)
      continue;
    source.path.erase(0, prefix.size());
    source.stamp = stamp_of(root / source.path);
  }
  model["sources"] = sources_json(sources);
  return replace_file(file, model.dump());
}

Expected<std::shared_ptr<const ResolvedSoftPkg>> read_runtime_model(const fs::path &spd_file) {
  const fs::path file = runtime_model_path(spd_file);
  std::ifstream in(file);
  if (!in)
    return model_error(file, "there is none");
  const Json model = Json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (model.is_discarded() || !model.is_object())
    return model_error(file, "it is not JSON");
  auto softpkg = from_runtime_model(model, spd_file);
  if (!softpkg)
    return softpkg;
  if (auto why = stale_because((*softpkg)->sources, spd_file); !why.empty())
    return model_error(file, why);
  return softpkg;
}

Expected<std::shared_ptr<const ResolvedSoftPkg>>
ComponentProfileLoader::load(const fs::path &spd_file) {
  fallback_reason_.clear();
  if (auto it = loaded_.find(spd_file); it != loaded_.end())
    return it->second;
  auto softpkg = read_runtime_model(spd_file);
  if (!softpkg) {
    fallback_reason_ = softpkg.error().to_string();
    if (!xml_)
      xml_.emplace();
    softpkg = xml_->load_softpkg(spd_file);
    if (!softpkg)
      return softpkg;
  }
  loaded_.emplace(spd_file, *softpkg);
  return softpkg;
}

} // namespace rsca::profile
