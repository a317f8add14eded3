// Files more than one test reads: the REDHAWK corpus's SDR root (RSCA_CORPUS_DIR), and a file's
// whole text. One copy each: the tests of one binary may share a translation unit (unity build).
#pragma once

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace rsca::test {

inline const std::filesystem::path kCorpus =
    std::filesystem::path(RSCA_CORPUS_DIR).lexically_normal();

inline std::string slurp(const std::filesystem::path &path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

} // namespace rsca::test
