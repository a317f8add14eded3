// Errors as values: what went wrong, where in which file, and which rule was broken.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <tl/expected.hpp>

namespace rsca {

struct SourceLocation {
  std::string file;
  int line = 0;   // 1-based; 0 when the problem concerns the whole file
  int column = 0; // 1-based; 0 when unknown
};

// Errors make a profile unusable. Warnings are inconsistencies a deployment would trip over but
// that do not stop the profile from being read (e.g. a connection naming a port its component
// lacks): `rsca validate` reports them, `--strict` and a launch treat them as errors.
enum class Severity : std::uint8_t { Error, Warning };

struct Diagnostic {
  SourceLocation where;
  std::string rule;    // short stable name of the rule broken, e.g. "schema", "dangling-ref"
  std::string message; // what was found and what was expected
  Severity severity = Severity::Error;
};

// One or more diagnostics; a failed operation returns this instead of a partial result.
class Error {
public:
  Error() = default;
  explicit Error(Diagnostic diagnostic) { diagnostics_.push_back(std::move(diagnostic)); }
  explicit Error(std::vector<Diagnostic> diagnostics) : diagnostics_(std::move(diagnostics)) {}

  const std::vector<Diagnostic> &diagnostics() const { return diagnostics_; }
  void add(Diagnostic diagnostic) { diagnostics_.push_back(std::move(diagnostic)); }
  void append(const Error &other);
  bool empty() const { return diagnostics_.empty(); }

  // "file:line:column: rule: message", one diagnostic per line.
  std::string to_string() const;

private:
  std::vector<Diagnostic> diagnostics_;
};

template <typename T>
using Expected = tl::expected<T, Error>;

inline tl::unexpected<Error> make_error(SourceLocation where, std::string rule,
                                        std::string message) {
  return tl::unexpected<Error>(
      Error(Diagnostic{std::move(where), std::move(rule), std::move(message)}));
}

std::string to_string(const Diagnostic &diagnostic);

} // namespace rsca
