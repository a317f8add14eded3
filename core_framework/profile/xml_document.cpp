#include "profile/xml_document.hpp"

#include <cctype>
#include <fstream>

#include <fmt/format.h>

#include "profile/xml_reader.hpp"

namespace rsca::profile {
namespace {

// Blanks the DOCTYPE declaration, if the prolog has one, keeping line breaks so every position
// Xerces reports stays where it was. rsca never uses DTDs, and Xerces 3.2 leaks the DTD grammar it
// builds for a DOCTYPE when parsing with a cached schema grammar (once per file), so the
// declaration is removed before Xerces sees it. A text whose prolog this does not understand (an
// unterminated DOCTYPE, a non-ASCII-compatible encoding) is left as it is for Xerces to judge.
void blank_doctype(std::string &text) {
  std::size_t i = text.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0;
  auto skip_past = [&](std::string_view end) {
    auto at = text.find(end, i);
    i = at == std::string::npos ? text.size() : at + end.size();
  };
  while (i < text.size()) {
    if (std::isspace(static_cast<unsigned char>(text[i]))) {
      ++i;
    } else if (text.compare(i, 2, "<?") == 0) {
      skip_past("?>");
    } else if (text.compare(i, 4, "<!--") == 0) {
      skip_past("-->");
    } else {
      break;
    }
  }
  if (text.compare(i, 9, "<!DOCTYPE") != 0)
    return;
  char quote = 0;
  int depth = 0;
  for (std::size_t j = i; j < text.size(); ++j) {
    char c = text[j];
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
      return;
    }
  }
}

std::string_view trim_xml_space(std::string_view s) {
  auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos)
    return {};
  auto last = s.find_last_not_of(" \t\r\n");
  return s.substr(first, last - first + 1);
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
  return std::string(trim_xml_space(text));
}

Expected<XmlDocument> read_xml_profile_text(std::string_view text, std::string file_name) {
  auto reader = XmlReader::acquire();
  if (!reader)
    return tl::unexpected(reader.error());
  std::string without_doctype(text);
  blank_doctype(without_doctype);
  return (*reader)->read(without_doctype, file_name);
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
