// libFuzzer target for profile reading (issue 23: "no crash on any input; every refusal names
// file, line, column and rule").
//
// Each input is read as one profile file named "fuzz.sad.xml": read_xml_profile_text (Xerces and
// the schemas, in librsca_xml_reader.so), then read_descriptor on the document when that succeeds.
// ASan and UBSan (the whole of rsca is built with them under RSCA_FUZZ) catch memory and undefined
// behaviour errors; this target traps when a refusal breaks the invariant: every diagnostic names
// the file, a rule and a message, and a line and column that are not negative (0 means the whole
// file, or unknown). The warnings of a document read are held to the same rule.
//
// Run: tools/fuzz [seconds]  (builds build-fuzz/ with clang and -DRSCA_FUZZ=ON, seeds a corpus
// from the repository's profiles and runs with tests/fuzz/profile.dict). A crash is written to
// build-fuzz/crash-*; reproduce it with build-fuzz/bin/rsca-profile-fuzzer build-fuzz/crash-<id>.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "common/diagnostic.hpp"
#include "profile/descriptor.hpp"
#include "profile/xml_document.hpp"
#include "profile/xml_reader.hpp"

namespace {

constexpr const char *kFileName = "fuzz.sad.xml";

// The module stays loaded for the whole run: read_xml_profile_text acquires the reader held here
// instead of loading and unloading Xerces and compiling the schemas again for every input.
std::shared_ptr<rsca::profile::XmlReader> g_reader;

void check(const rsca::Diagnostic &d, const char *where) {
  if (!d.where.file.empty() && !d.rule.empty() && !d.message.empty() && d.where.line >= 0 &&
      d.where.column >= 0)
    return;
  std::fprintf(stderr, "profile_fuzzer: %s diagnostic breaks the invariant: %s\n", where,
               rsca::to_string(d).c_str());
  __builtin_trap();
}

void check(const rsca::Error &error, const char *where) {
  // A refusal gives at least one reason.
  if (error.empty()) {
    std::fprintf(stderr, "profile_fuzzer: %s refusal without a diagnostic\n", where);
    __builtin_trap();
  }
  for (const auto &d : error.diagnostics())
    check(d, where);
}

} // namespace

extern "C" int LLVMFuzzerInitialize(int * /*argc*/, char *** /*argv*/) {
  auto reader = rsca::profile::XmlReader::acquire();
  if (!reader) {
    std::fprintf(stderr, "profile_fuzzer: %s\n", reader.error().to_string().c_str());
    std::abort();
  }
  g_reader = *reader;
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char *>(data), size);
  auto document = rsca::profile::read_xml_profile_text(text, kFileName);
  if (!document) {
    check(document.error(), "read_xml_profile_text");
    return 0;
  }
  for (const auto &w : document->warnings)
    check(w, "read_xml_profile_text warning");
  auto descriptor = rsca::profile::read_descriptor(*document);
  if (!descriptor)
    check(descriptor.error(), "read_descriptor");
  return 0;
}
