// A profile file read and validated against rsca's XML Schemas, as a small element tree that
// remembers where each element stands so later checks can point at file, line and column.
// No Xerces type leaves this module.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/diagnostic.hpp"

namespace rsca::profile {

struct XmlElement {
  std::string name;
  std::vector<std::pair<std::string, std::string>> attributes;
  std::string text; // character data directly inside this element
  std::vector<XmlElement> children;
  int line = 0;
  int column = 0;

  // The attribute's value, or nullptr when absent.
  const std::string *attribute(std::string_view attribute_name) const;
  // The attribute's value, or "" when absent (for attributes the schema requires).
  const std::string &attr(std::string_view attribute_name) const;
  // The first child of that name, or nullptr.
  const XmlElement *child(std::string_view child_name) const;
  // The text of the first child of that name, trimmed, or "" when absent.
  std::string child_text(std::string_view child_name) const;
  // This element's text with surrounding white space removed.
  std::string trimmed_text() const;
};

struct XmlDocument {
  std::string file; // as given, for messages
  XmlElement root;
  // What the schemas refuse but REDHAWK reads, read anyway (e.g. an attribute no schema declares,
  // which is ignored): `rsca validate` shows these, `--strict` refuses them.
  std::vector<Diagnostic> warnings;
  // Whether the file carries a DOCTYPE: REDHAWK's tools (and SCA 2.2.2's) write the SCA DTD's,
  // rsca's templates and profiles none. A profile written for REDHAWK is read as REDHAWK reads
  // it (what REDHAWK tolerates only warns); one written for rsca is read strictly (what would
  // only warn is an error), see docs/profiles.md.
  bool redhawk = false;
};

// The largest profile accepted; a larger file is refused before parsing, since no descriptor
// comes close and parsing one would only waste memory.
inline constexpr std::uintmax_t kMaxProfileBytes = 8u * 1024 * 1024;

// Reads and validates one profile. Fails with every schema violation found (each located), or
// with the first well-formedness error; never yields a partial document.
Expected<XmlDocument> read_xml_profile(const std::filesystem::path &file);

// Same, for text already in memory; `file_name` is used in messages.
Expected<XmlDocument> read_xml_profile_text(std::string_view text, std::string file_name);

} // namespace rsca::profile
