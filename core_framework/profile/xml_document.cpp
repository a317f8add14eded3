#include "profile/xml_document.hpp"
#include "common/text.hpp"

#include <cctype>
#include <fstream>
#include <optional>
#include <utility>

#include <fmt/format.h>

#include "profile/xml_reader.hpp"

namespace rsca::profile {
namespace {

// DOCTYPE declarations are blanked before Xerces sees them, keeping line breaks so every position
// Xerces reports stays where it was. rsca never uses DTDs, and Xerces 3.2 leaks the DTD grammar it
// builds for a DOCTYPE when parsing with a cached schema grammar (once per file). A text whose
// prolog this does not understand (an unterminated DOCTYPE, a non-ASCII-compatible encoding) is
// left as it is for Xerces to judge.

// Blanks the declaration starting at `i` (up to its closing '>' outside quotes and its internal
// subset) and returns where it ended.
std::size_t blank_declaration(std::string &text, std::size_t i) {
  char quote = 0;
  int depth = 0;
  for (std::size_t j = i; j < text.size(); ++j) {
    const char c = text[j];
    if (quote != 0) {
      quote = c == quote ? 0 : quote;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '[') {
      ++depth;
    } else if (c == ']') {
      --depth;
    } else if (c == '>' && depth == 0) {
      for (std::size_t k = i; k <= j; ++k)
        if (text[k] != '\n' && text[k] != '\r')
          text[k] = ' ';
      return j + 1;
    }
  }
  return text.size();
}

// Where the XML declaration starting at `i` ends: its values are quoted, and Xerces reads them so
// (a "?>" inside quotes does not end it), so this reads it the same way.
std::size_t end_of_xml_declaration(const std::string &text, std::size_t i) {
  char quote = 0;
  for (std::size_t j = i + 5; j < text.size(); ++j) {
    const char c = text[j];
    if (quote != 0)
      quote = c == quote ? 0 : quote;
    else if (c == '"' || c == '\'')
      quote = c;
    else if (c == '?' && j + 1 < text.size() && text[j + 1] == '>')
      return j + 2;
  }
  return text.size();
}

// Blanks the DOCTYPE declaration in the prolog (keeping line breaks, so positions stay), and
// returns where a second one starts, if any: XML allows one, and Xerces leaks the declaration of
// one it sees, so none reaches it.
std::optional<std::size_t> blank_doctype(std::string &text) {
  std::size_t i = text.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0;
  auto skip_past = [&](std::string_view start, std::string_view end) {
    auto at = text.find(end, i + start.size());
    i = at == std::string::npos ? text.size() : at + end.size();
  };
  bool blanked = false;
  while (i < text.size()) {
    if (std::isspace(static_cast<unsigned char>(text[i]))) {
      ++i;
    } else if (text.compare(i, 5, "<?xml") == 0 && i + 5 < text.size() &&
               std::isspace(static_cast<unsigned char>(text[i + 5]))) {
      i = end_of_xml_declaration(text, i);
    } else if (text.compare(i, 2, "<?") == 0) {
      skip_past("<?", "?>");
    } else if (text.compare(i, 4, "<!--") == 0) {
      skip_past("<!--", "-->");
    } else if (text.compare(i, 9, "<!DOCTYPE") == 0) {
      if (blanked)
        return i;
      i = blank_declaration(text, i);
      blanked = true;
    } else {
      break;
    }
  }
  return std::nullopt;
}

// The 1-based line and column of byte `at`.
std::pair<int, int> position_of(std::string_view text, std::size_t at) {
  int line = 1;
  std::size_t line_start = 0;
  for (std::size_t k = 0; k < at && k < text.size(); ++k)
    if (text[k] == '\n') {
      ++line;
      line_start = k + 1;
    }
  return {line, static_cast<int>(at - line_start) + 1};
}

} // namespace

const std::string *XmlElement::attribute(std::string_view attribute_name) const {
  for (const auto &[key, value] : attributes)
    if (key == attribute_name)
      return &value;
  return nullptr;
}

const std::string &XmlElement::attr(std::string_view attribute_name) const {
  static const std::string empty;
  const std::string *value = attribute(attribute_name);
  return value != nullptr ? *value : empty;
}

const XmlElement *XmlElement::child(std::string_view child_name) const {
  for (const auto &c : children)
    if (c.name == child_name)
      return &c;
  return nullptr;
}

std::string XmlElement::child_text(std::string_view child_name) const {
  const XmlElement *c = child(child_name);
  return c != nullptr ? c->trimmed_text() : std::string();
}

std::string XmlElement::trimmed_text() const {
  return std::string(trim(text));
}

Expected<XmlDocument> read_xml_profile_text(std::string_view text, std::string file_name) {
  auto reader = XmlReader::acquire();
  if (!reader)
    return tl::unexpected(reader.error());
  std::string without_doctype(text);
  auto second = blank_doctype(without_doctype);
  // Any DOCTYPE left (a second one, or one after a prolog this scan reads otherwise than Xerces
  // would) is refused before Xerces sees it: no profile has one there (REDHAWK's have one, at
  // the start), and Xerces leaks what it reads of one.
  if (!second)
    if (const auto left = without_doctype.find("<!DOCTYPE"); left != std::string::npos)
      second = left;
  if (second) {
    const auto [line, column] = position_of(text, *second);
    return make_error({file_name, line, column}, "xml",
                      "a DOCTYPE declaration here: a profile has at most one, at its start");
  }
  auto document = (*reader)->read(without_doctype, file_name);
  if (document)
    document->redhawk = without_doctype != text; // a DOCTYPE was blanked
  return document;
}

Expected<XmlDocument> read_xml_profile(const std::filesystem::path &file) {
  const std::string name = file.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    return make_error({name, 0, 0}, "missing-file", "no such file");
  auto size = std::filesystem::file_size(file, ec);
  if (ec)
    return make_error({name, 0, 0}, "io", ec.message());
  if (size > kMaxProfileBytes)
    return make_error({name, 0, 0}, "too-large",
                      fmt::format("the file is {} bytes; profiles are limited to {} bytes", size,
                                  kMaxProfileBytes));
  std::ifstream in(file, std::ios::binary);
  if (!in)
    return make_error({name, 0, 0}, "io", "cannot open the file for reading");
  std::string text(static_cast<std::size_t>(size), '\0');
  in.read(text.data(), static_cast<std::streamsize>(size));
  if (!in)
    return make_error({name, 0, 0}, "io", "cannot read the file");
  return read_xml_profile_text(text, name);
}

} // namespace rsca::profile
