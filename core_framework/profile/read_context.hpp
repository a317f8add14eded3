// Internal to the profile readers: the state of reading one file, and readers of the elements
// several descriptor types share. The schema has already checked structure; what is left is
// turning text into typed values and reporting, with locations, what the schema cannot see.
#pragma once

#include <set>
#include <string>
#include <string_view>

#include <fmt/format.h>

#include "common/diagnostic.hpp"
#include "common/units.hpp"
#include "profile/assembly.hpp"
#include "profile/prf.hpp"
#include "profile/property_refs.hpp"
#include "profile/xml_document.hpp"

namespace rsca::profile::detail {

class ReadContext {
public:
  explicit ReadContext(std::string file) : file_(std::move(file)) {}
  // Reading `document`, whose own warnings (the XML reader's) come first.
  explicit ReadContext(const XmlDocument &document)
      : file_(document.file), warnings_(document.warnings), redhawk_(document.redhawk) {}

  const std::string &file() const { return file_; }
  bool redhawk() const { return redhawk_; }
  SourceLocation at(const XmlElement &e) const { return {file_, e.line, e.column}; }

  void fail(const XmlElement &e, std::string rule, std::string message) {
    report({at(e), std::move(rule), std::move(message)});
  }
  void report(Diagnostic diagnostic) { error_.add(std::move(diagnostic)); }
  bool ok() const { return error_.empty(); }
  Error take_error() { return std::move(error_); }

  // Something REDHAWK reads and rsca reads too, but that deserves a look (an unknown value
  // ignored, a form REDHAWK tolerates): a warning, an error only under `--strict`.
  void warn(const XmlElement &e, std::string rule, std::string message) {
    warnings_.push_back({at(e), std::move(rule), std::move(message), Severity::Warning});
  }
  // REDHAWK reads any text in a file-type attribute (componentfile/@type "SPD", propertyfile's
  // "PRF", ...); rsca too, warning about one that is not the type the file must have.
  void expect_type(const XmlElement &e, std::string_view expected) {
    const std::string *type = e.attribute("type");
    if (type != nullptr && *type != expected)
      warn(
          e, "unknown-value",
          fmt::format("<{}> type \"{}\" is not {}: read as {}", e.name, *type, expected, expected));
  }

  void warn_at(Diagnostic diagnostic) {
    diagnostic.severity = Severity::Warning;
    warnings_.push_back(std::move(diagnostic));
  }
  std::vector<Diagnostic> take_warnings() { return std::move(warnings_); }

  // Reports a second use of `id` among `kind` (e.g. "componentinstantiation id").
  void require_unique(std::set<std::string> &seen, const std::string &id, const XmlElement &e,
                      std::string_view kind) {
    require_unique(seen, id, at(e), kind);
  }
  void require_unique(std::set<std::string> &seen, const std::string &id,
                      const SourceLocation &where, std::string_view kind) {
    if (!seen.insert(id).second)
      report({where, "duplicate-id", fmt::format("{} \"{}\" is defined more than once", kind, id)});
  }

  // The value parsed by `parse` from attribute `name`, or nullopt (reported) when it is invalid
  // or (silently) when absent.
  template <typename Parse>
  auto optional_attr(const XmlElement &e, std::string_view name, Parse parse)
      -> std::optional<typename decltype(parse(std::string_view{}))::value_type> {
    const std::string *text = e.attribute(name);
    if (text == nullptr)
      return std::nullopt;
    auto parsed = parse(*text);
    if (!parsed) {
      fail(e, "value", fmt::format("attribute {}: {}", name, parsed.error()));
      return std::nullopt;
    }
    return *parsed;
  }

  std::optional<Duration> duration_attr(const XmlElement &e, std::string_view name) {
    return optional_attr(e, name, parse_duration);
  }

  // The value parsed by `parse` from the text of child `name`, or nullopt (reported when invalid).
  template <typename Parse>
  auto optional_child(const XmlElement &e, std::string_view name, Parse parse)
      -> std::optional<typename decltype(parse(std::string_view{}))::value_type> {
    const XmlElement *c = e.child(name);
    if (c == nullptr)
      return std::nullopt;
    auto parsed = parse(c->trimmed_text());
    if (!parsed) {
      fail(*c, "value", fmt::format("{}: {}", name, parsed.error()));
      return std::nullopt;
    }
    return *parsed;
  }

private:
  std::string file_;
  Error error_;
  std::vector<Diagnostic> warnings_;
  bool redhawk_ = false;
};

// The descriptor read, with the warnings found reading it; or every error found.
template <typename R>
Expected<R> finish(ReadContext &ctx, R &&result) {
  if (!ctx.ok())
    return tl::unexpected(ctx.take_error());
  result.warnings = ctx.take_warnings();
  result.redhawk = ctx.redhawk();
  return std::forward<R>(result);
}

LocalFile read_localfile(ReadContext &ctx, const XmlElement &holder);
PropertyRef read_property_ref(ReadContext &ctx, const XmlElement &e);
bool is_property_ref(std::string_view element_name);
std::vector<PropertyRef> read_property_refs(ReadContext &ctx, const XmlElement *holder);

std::vector<ComponentFile> read_component_files(ReadContext &ctx, const XmlElement *holder);
ComponentPlacement read_component_placement(ReadContext &ctx, const XmlElement &e);
std::vector<Connection> read_connections(ReadContext &ctx, const XmlElement *holder);

// Checks a SAD's or DCD's references between its own parts (component files, instantiations,
// connection ends) and the uniqueness of their ids.
void check_assembly_references(ReadContext &ctx, const std::vector<ComponentFile> &files,
                               const std::vector<ComponentPlacement> &placements,
                               const std::vector<Connection> &connections);

// Reads a PRF value text of `spec`, reporting a bad value at `e`.
std::optional<Scalar> read_scalar(ReadContext &ctx, const XmlElement &e, TypeSpec spec,
                                  const std::string &text, std::string_view what);

} // namespace rsca::profile::detail
