// What the malformed-profile tests share: the fixtures under tests/data/malformed/, checks of a
// diagnostic (rule, file, line, column, message fragments), and files for the inputs made on the
// spot (in a TempDir, temp_dir.hpp). Used by malformed_test.cpp (syntax, schema, values), and
// malformed_references_test.cpp and malformed_hostile_test.cpp.
#pragma once

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

#include <catch2/catch.hpp>

#include "profile/descriptor.hpp"
#include "temp_dir.hpp"

namespace rsca::test {

using namespace rsca::profile;
using Catch::Contains;

inline std::filesystem::path fixture(std::string_view relative) {
  return std::filesystem::path(RSCA_TEST_DATA_DIR) / "malformed" / std::filesystem::path(relative);
}

// The name ProfileLoader gives a file in its diagnostics.
inline std::string loader_name(const std::filesystem::path &file) {
  return std::filesystem::absolute(file).lexically_normal().string();
}

// The error of a result that must have failed: no value, and at least one diagnostic.
template <typename T>
const Error &error_of(const Expected<T> &result) {
  REQUIRE_FALSE(result.has_value());
  REQUIRE_FALSE(result.error().empty());
  return result.error();
}

// The first diagnostic breaking `rule`.
inline const Diagnostic &find_rule(const Error &error, std::string_view rule) {
  INFO("diagnostics:\n" << error.to_string());
  const auto &all = error.diagnostics();
  auto it =
      std::find_if(all.begin(), all.end(), [&](const Diagnostic &d) { return d.rule == rule; });
  REQUIRE(it != all.end());
  return *it;
}

// Checks one diagnostic: rule, severity, file, line, column and message fragments.
inline void check(const Diagnostic &d, std::string_view rule, const std::string &file, int line,
                  int column, std::initializer_list<std::string_view> fragments,
                  Severity severity = Severity::Error) {
  INFO("diagnostic: " << to_string(d));
  CHECK(d.rule == rule);
  CHECK(d.severity == severity);
  CHECK(d.where.file == file);
  CHECK(d.where.line == line);
  CHECK(d.where.column == column);
  for (auto fragment : fragments)
    CHECK_THAT(d.message, Contains(std::string(fragment)));
}

// Reads one fixture on its own and checks its first diagnostic; returns all of them.
inline std::vector<Diagnostic>
single_file_error(const std::filesystem::path &file, std::string_view rule, int line, int column,
                  std::initializer_list<std::string_view> fragments) {
  const auto result = read_descriptor(file);
  const Error &error = error_of(result);
  INFO("diagnostics:\n" << error.to_string());
  check(error.diagnostics().front(), rule, file.string(), line, column, fragments);
  return error.diagnostics();
}

inline void write_file(const std::filesystem::path &file, std::string_view text) {
  std::ofstream out(file, std::ios::binary);
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  REQUIRE(out.good());
}

// A valid SAD with `padding` bytes of comment inside, so tests can make it any size.
inline std::string padded_sad(std::size_t padding) {
  const std::string head = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<!--";
  const std::string tail = "-->\n"
                           "<softwareassembly id=\"DCE:big\" name=\"big\">\n"
                           "  <componentfiles>\n"
                           "    <componentfile id=\"comp_spd\" type=\"SPD\">\n"
                           "      <localfile name=\"/components/comp/comp.spd.xml\"/>\n"
                           "    </componentfile>\n"
                           "  </componentfiles>\n"
                           "  <partitioning>\n"
                           "    <componentplacement>\n"
                           "      <componentfileref refid=\"comp_spd\"/>\n"
                           "      <componentinstantiation id=\"comp_1\"/>\n"
                           "    </componentplacement>\n"
                           "  </partitioning>\n"
                           "  <assemblycontroller>\n"
                           "    <componentinstantiationref refid=\"comp_1\"/>\n"
                           "  </assemblycontroller>\n"
                           "</softwareassembly>\n";
  std::string text = head;
  text.append(padding, 'x');
  text += tail;
  return text;
}

} // namespace rsca::test
