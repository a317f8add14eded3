#include "common/diagnostic.hpp"

#include <fmt/format.h>

namespace rsca {

std::string to_string(const Diagnostic &d) {
  std::string place = d.where.file;
  if (d.where.line > 0) {
    place += fmt::format(":{}", d.where.line);
    if (d.where.column > 0)
      place += fmt::format(":{}", d.where.column);
  }
  const char *level = d.severity == Severity::Warning ? "warning: " : "";
  return fmt::format("{}: {}{}: {}", place, level, d.rule, d.message);
}

void Error::append(const Error &other) {
  diagnostics_.insert(diagnostics_.end(), other.diagnostics_.begin(), other.diagnostics_.end());
}

std::string Error::to_string() const {
  std::string out;
  for (const auto &d : diagnostics_) {
    if (!out.empty())
      out += '\n';
    out += rsca::to_string(d);
  }
  return out;
}

} // namespace rsca
