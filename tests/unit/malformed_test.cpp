// Malformed profiles: each bad input must fail with the rule it breaks, located at the file,
// line and column a user needs to fix it, with a message saying what was expected; no bad file
// yields a partial model or brings the process down. Fixtures: tests/data/malformed/ (one
// defect each, named by the comment at its top); cases needing other files have their own SDR
// root (<case>/dom/...); huge and deeply nested files are generated in a temporary folder.
#include "profile/descriptor.hpp"
#include "profile/profile_loader.hpp"
#include "profile/xml_document.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <random>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace fs = std::filesystem;
using namespace rsca;
using namespace rsca::profile;
using Catch::Contains;

namespace {

fs::path fixture(std::string_view relative) {
  return fs::path(RSCA_TEST_DATA_DIR) / "malformed" / fs::path(relative);
}

// The name ProfileLoader gives a file in its diagnostics.
std::string loader_name(const fs::path &file) {
  return fs::absolute(file).lexically_normal().string();
}

// The error of a result that must have failed: no value, and at least one diagnostic.
template <typename T>
const Error &error_of(const Expected<T> &result) {
  REQUIRE_FALSE(result.has_value());
  REQUIRE_FALSE(result.error().empty());
  return result.error();
}

// The first diagnostic breaking `rule`.
const Diagnostic &find_rule(const Error &error, std::string_view rule) {
  INFO("diagnostics:\n" << error.to_string());
  const auto &all = error.diagnostics();
  auto it =
      std::find_if(all.begin(), all.end(), [&](const Diagnostic &d) { return d.rule == rule; });
  REQUIRE(it != all.end());
  return *it;
}

// Checks one diagnostic: rule, severity, file, line, column and message fragments.
void check(const Diagnostic &d, std::string_view rule, const std::string &file, int line,
           int column, std::initializer_list<std::string_view> fragments) {
  INFO("diagnostic: " << to_string(d));
  CHECK(d.rule == rule);
  CHECK(d.severity == Severity::Error);
  CHECK(d.where.file == file);
  CHECK(d.where.line == line);
  CHECK(d.where.column == column);
  for (auto fragment : fragments)
    CHECK_THAT(d.message, Contains(std::string(fragment)));
}

// Reads one fixture on its own and checks its first diagnostic; returns all of them.
std::vector<Diagnostic> single_file_error(const fs::path &file, std::string_view rule, int line,
                                          int column,
                                          std::initializer_list<std::string_view> fragments) {
  const auto result = read_descriptor(file);
  const Error &error = error_of(result);
  INFO("diagnostics:\n" << error.to_string());
  check(error.diagnostics().front(), rule, file.string(), line, column, fragments);
  return error.diagnostics();
}

// A folder of its own under the system's temporary directory, removed with everything in it.
class TempDir {
public:
  TempDir() {
    std::random_device random;
    path_ = fs::temp_directory_path() /
            ("rsca-malformed-" + std::to_string(random()) + "-" + std::to_string(random()));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir &) = delete;
  TempDir &operator=(const TempDir &) = delete;

  const fs::path &path() const { return path_; }

private:
  fs::path path_;
};

void write_file(const fs::path &file, std::string_view text) {
  std::ofstream out(file, std::ios::binary);
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  REQUIRE(out.good());
}

// A valid SAD with `padding` bytes of comment inside, so tests can make it any size.
std::string padded_sad(std::size_t padding) {
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

} // namespace

// ---------------------------------------------------------------------------------------------
// Bad XML: the first well-formedness error, rule "xml".

TEST_CASE("an unclosed tag is reported where the input ends", "[malformed][xml]") {
  single_file_error(fixture("xml/unclosed_tag.sad.xml"), "xml", 10, 1,
                    {"input ended before all started tags were ended", "'partitioning'"});
}

TEST_CASE("a mismatched end tag is reported at that tag", "[malformed][xml]") {
  single_file_error(fixture("xml/mismatched_end_tag.sad.xml"), "xml", 8, 5,
                    {"expected end of tag 'componentfiles'"});
}

TEST_CASE("an element after the root element is reported where it starts", "[malformed][xml]") {
  single_file_error(fixture("xml/garbage_after_root.sad.xml"), "xml", 19, 1,
                    {"comment or processing instruction expected"});
}

TEST_CASE("a character XML forbids is reported where it stands", "[malformed][xml]") {
  single_file_error(fixture("xml/invalid_character.sad.xml"), "xml", 13, 25,
                    {"invalid character 0x1"});
}

TEST_CASE("an empty or blank file is an XML error on line 1", "[malformed][xml]") {
  SECTION("0 bytes") {
    const fs::path file = fixture("xml/empty.sad.xml");
    REQUIRE(fs::file_size(file) == 0);
    single_file_error(file, "xml", 1, 1, {"the file is empty", "expected an XML profile"});
  }
  SECTION("white space only") {
    const fs::path file = fixture("xml/whitespace_only.sad.xml");
    REQUIRE(fs::file_size(file) > 0);
    single_file_error(file, "xml", 1, 1, {"the file is empty", "expected an XML profile"});
  }
  SECTION("text in memory") {
    for (std::string_view text : {std::string_view(), std::string_view(" \n\t\r\n")}) {
      auto result = read_xml_profile_text(text, "memory.sad.xml");
      check(error_of(result).diagnostics().front(), "xml", "memory.sad.xml", 1, 1,
            {"the file is empty"});
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Schema violations, rule "schema".

TEST_CASE("an unknown element is reported at that element", "[malformed][schema]") {
  const auto all = single_file_error(fixture("schema/unknown_element.sad.xml"), "schema", 15, 11,
                                     {"<bogus> is not an element"});
  // Only the element itself: its parent's content model fails for no other reason.
  CHECK(all.size() == 1);
}

TEST_CASE("an unknown attribute is reported at its element", "[malformed][schema]") {
  single_file_error(fixture("schema/unknown_attribute.sad.xml"), "schema", 12, 58,
                    {"attribute 'colour' is not declared for element 'componentinstantiation'"});
}

TEST_CASE("a missing required attribute is reported at its element", "[malformed][schema]") {
  single_file_error(fixture("schema/missing_required_attribute.sad.xml"), "schema", 11, 26,
                    {"missing required attribute 'refid'"});
}

TEST_CASE("elements out of order are reported with the expected order", "[malformed][schema]") {
  const fs::path file = fixture("schema/wrong_element_order.sad.xml");
  auto result = read_descriptor(file);
  const Diagnostic &d = error_of(result).diagnostics().front();
  INFO("diagnostic: " << to_string(d));
  CHECK(d.rule == "schema");
  CHECK(d.where.file == file.string());
  // The line is not checked yet: the error is reported at the root's end tag (line 18), not at
  // the misplaced <assemblycontroller> (line 9).
  CHECK_THAT(d.message, Contains("element 'assemblycontroller' is not allowed"));
  CHECK_THAT(d.message, Contains("componentfiles,partitioning,assemblycontroller"));
}

TEST_CASE("a root element that is no profile is refused", "[malformed][schema]") {
  single_file_error(fixture("schema/wrong_root.sad.xml"), "schema", 3, 7,
                    {"<html> is not the root of a domain profile", "softwareassembly (SAD)"});
}

// ---------------------------------------------------------------------------------------------
// Values of the wrong type.

TEST_CASE("a non-numeric startorder is a schema error at its element", "[malformed][value]") {
  single_file_error(fixture("value/startorder_not_integer.sad.xml"), "schema", 12, 61,
                    {"'abc' is not an integer"});
}

TEST_CASE("a PRF long whose value is not a number", "[malformed][value]") {
  single_file_error(fixture("value/long_not_a_number.prf.xml"), "value", 5, 12,
                    {"value of \"gain\"", "\"abc\" is not a valid long"});
}

TEST_CASE("a boolean that is neither true nor false", "[malformed][value]") {
  SECTION("a PRF boolean property's value") {
    single_file_error(fixture("value/boolean_maybe.prf.xml"), "value", 5, 12,
                      {"value of \"enabled\"", "\"maybe\" is not a boolean (true or false)"});
  }
  SECTION("an xs:boolean attribute") {
    single_file_error(fixture("value/boolean_attribute_maybe.prf.xml"), "schema", 4, 71,
                      {"'maybe' is invalid boolean"});
  }
}

TEST_CASE("a duration with an unknown unit", "[malformed][value]") {
  single_file_error(fixture("value/duration_parsecs.sad.xml"), "schema", 13, 51,
                    {"'10 parsecs' is not a duration such as 10ms"});
}

TEST_CASE("a SAD override giving a ulong property -1", "[malformed][value]") {
  const fs::path root = fixture("value/override_ulong_negative");
  const fs::path sad = root / "dom/waveforms/app/app.sad.xml";
  ProfileLoader loader(root);
  auto result = loader.load_application(sad);
  check(find_rule(error_of(result), "value"), "value", loader_name(sad), 14, 48,
        {"property \"count\"", "\"-1\" is out of range for ulong (0..4294967295)"});
}

// ---------------------------------------------------------------------------------------------
// Values out of range.

TEST_CASE("a PRF short default of 70000", "[malformed][range]") {
  single_file_error(fixture("range/short_overflow.prf.xml"), "value", 5, 12,
                    {"\"70000\" is out of range for short (-32768..32767)"});
}

TEST_CASE("a PRF default outside the property's own range", "[malformed][range]") {
  single_file_error(fixture("range/outside_prf_range.prf.xml"), "range", 5, 12,
                    {"value 150 of \"volume\" is outside its range 0..100"});
}

TEST_CASE("a SAD override outside the PRF range", "[malformed][range]") {
  const fs::path root = fixture("range/override_outside_range");
  const fs::path sad = root / "dom/waveforms/app/app.sad.xml";
  ProfileLoader loader(root);
  auto result = loader.load_application(sad);
  const Error &error = error_of(result);
  REQUIRE(error.diagnostics().size() == 1);
  check(error.diagnostics().front(), "range", loader_name(sad), 14, 48,
        {"property \"level\"", "11 is outside its range 0..10"});
}

// ---------------------------------------------------------------------------------------------
// Dangling references.

TEST_CASE("a componentfileref naming no componentfile", "[malformed][dangling]") {
  single_file_error(
      fixture("dangling/componentfileref.sad.xml"), "dangling-ref", 11, 46,
      {"componentfileref refid \"missing_spd\" names no componentfile", "(known: comp_spd)"});
}

TEST_CASE("a connection naming no componentinstantiation", "[malformed][dangling]") {
  const fs::path file = fixture("dangling/connection_ref.sad.xml");
  auto result = read_descriptor(file);
  const Error &error = error_of(result);
  REQUIRE(error.diagnostics().size() == 1);
  const Diagnostic &d = error.diagnostics().front();
  INFO("diagnostic: " << to_string(d));
  CHECK(d.rule == "dangling-ref");
  CHECK(d.where.file == file.string());
  CHECK(d.where.line == 26); // the <componentinstantiationref refid="ghost_1"/> itself
  CHECK_THAT(d.message,
             Contains("connection \"link\" refers to componentinstantiation \"ghost_1\""));
  CHECK_THAT(d.message, Contains("which this file does not define"));
}

TEST_CASE("an application name that is a path", "[malformed][value]") {
  single_file_error(fixture("value/application_name_path.sad.xml"), "application-name", 4, 39,
                    {"the application \"../../victim\" is not a name", "'.'"});
}

TEST_CASE("an assemblycontroller naming no componentinstantiation", "[malformed][dangling]") {
  single_file_error(fixture("dangling/assemblycontroller.sad.xml"), "dangling-ref", 16, 49,
                    {"assemblycontroller names componentinstantiation \"ghost_1\"",
                     "which this SAD does not define"});
}

TEST_CASE("an SPD implref naming an implementation the dependency lacks", "[malformed][dangling]") {
  const fs::path root = fixture("dangling/implref");
  const fs::path spd = root / "dom/components/comp/comp.spd.xml";
  ProfileLoader loader(root);
  auto result = loader.load_softpkg(spd);
  const Diagnostic &d = find_rule(error_of(result), "dangling-ref");
  INFO("diagnostic: " << to_string(d));
  CHECK(d.where.file == loader_name(spd));
  CHECK(d.where.line == 14); // the <implref refid="fpga"/> itself
  CHECK_THAT(d.message, Contains("implref \"fpga\" names no implementation of lib"));
  CHECK_THAT(d.message, Contains("(it has: cpp)"));
}

TEST_CASE("a SAD override of a property the PRF does not define", "[malformed][dangling]") {
  const fs::path root = fixture("dangling/unknown_property");
  const fs::path sad = root / "dom/waveforms/app/app.sad.xml";
  ProfileLoader loader(root);
  auto result = loader.load_application(sad);
  const Error &error = error_of(result);
  REQUIRE(error.diagnostics().size() == 1);
  check(error.diagnostics().front(), "unknown-property", loader_name(sad), 14, 46,
        {"componentinstantiation \"comp_1\"", "property \"gain\" is not defined by comp.prf.xml"});
}

// ---------------------------------------------------------------------------------------------
// Duplicate ids.

TEST_CASE("two componentinstantiations with one id", "[malformed][duplicate]") {
  single_file_error(fixture("duplicate/instantiation_id.sad.xml"), "duplicate-id", 16, 44,
                    {"componentinstantiation id \"comp_1\" is defined more than once"});
}

TEST_CASE("two PRF properties with one id", "[malformed][duplicate]") {
  single_file_error(fixture("duplicate/property_id.prf.xml"), "duplicate-id", 8, 53,
                    {"property id \"gain\" is defined more than once"});
}

// ---------------------------------------------------------------------------------------------
// Missing files, cycles, wrong descriptor types: problems between files.

TEST_CASE("a SAD naming an SPD that does not exist", "[malformed][missing-file]") {
  const fs::path root = fixture("missing_file/spd");
  const fs::path sad = root / "dom/waveforms/app/app.sad.xml";
  ProfileLoader loader(root);
  auto result = loader.load_application(sad);
  const Error &error = error_of(result);
  REQUIRE(error.diagnostics().size() == 1);
  check(error.diagnostics().front(), "missing-file", loader_name(sad), 6, 56,
        {"the file named here does not exist",
         loader_name(root / "dom/components/comp/comp.spd.xml")});
}

TEST_CASE("an SPD naming a PRF that does not exist", "[malformed][missing-file]") {
  const fs::path root = fixture("missing_file/prf");
  const fs::path spd = root / "dom/components/comp/comp.spd.xml";
  const std::string prf = loader_name(root / "dom/components/comp/comp.prf.xml");

  SECTION("the package on its own") {
    ProfileLoader loader(root);
    auto result = loader.load_softpkg(spd);
    const Error &error = error_of(result);
    REQUIRE(error.diagnostics().size() == 1);
    check(error.diagnostics().front(), "missing-file", loader_name(spd), 8, 37,
          {"the file named here does not exist", prf});
  }
  SECTION("through an application: the SPD's error, then a note where the SAD names it") {
    const fs::path sad = root / "dom/waveforms/app/app.sad.xml";
    ProfileLoader loader(root);
    auto result = loader.load_application(sad);
    const Error &error = error_of(result);
    REQUIRE(error.diagnostics().size() == 2);
    check(error.diagnostics()[0], "missing-file", loader_name(spd), 8, 37, {prf});
    check(error.diagnostics()[1], "invalid-ref", loader_name(sad), 6, 56,
          {"is invalid", loader_name(spd)});
  }
}

TEST_CASE("softpkg dependencies forming a cycle", "[malformed][dependency-cycle]") {
  const fs::path root = fixture("cycle");
  const fs::path a = root / "dom/deps/a/a.spd.xml";
  const fs::path b = root / "dom/deps/b/b.spd.xml";

  SECTION("starting from a") {
    ProfileLoader loader(root);
    auto result = loader.load_softpkg(a);
    const Error &error = error_of(result);
    check(find_rule(error, "dependency-cycle"), "dependency-cycle", loader_name(b), 13, 46,
          {"a.spd.xml -> b.spd.xml -> a.spd.xml"});
    check(find_rule(error, "invalid-ref"), "invalid-ref", loader_name(a), 13, 46, {loader_name(b)});
  }
  SECTION("starting from b") {
    ProfileLoader loader(root);
    auto result = loader.load_softpkg(b);
    check(find_rule(error_of(result), "dependency-cycle"), "dependency-cycle", loader_name(a), 13,
          46, {"b.spd.xml -> a.spd.xml -> b.spd.xml"});
  }
}

TEST_CASE("a SAD componentfile naming a PRF instead of an SPD", "[malformed][wrong-descriptor]") {
  const fs::path root = fixture("wrong_descriptor");
  const fs::path sad = root / "dom/waveforms/app/app.sad.xml";
  ProfileLoader loader(root);
  auto result = loader.load_application(sad);
  const Error &error = error_of(result);
  REQUIRE(error.diagnostics().size() == 1);
  check(error.diagnostics().front(), "wrong-descriptor", loader_name(sad), 6, 56,
        {"SPD", loader_name(root / "dom/components/comp/comp.prf.xml") + " is a PRF"});
}

TEST_CASE("an application outside any SDR root", "[malformed][sdrroot]") {
  // Generated, since the source tree itself might lie below a folder named dom or dev.
  TempDir dir;
  const fs::path sad = dir.path() / "app.sad.xml";
  write_file(sad, padded_sad(0));
  ProfileLoader loader;
  auto result = loader.load_application(sad);
  const Error &error = error_of(result);
  REQUIRE(error.diagnostics().size() == 1);
  check(error.diagnostics().front(), "sdrroot", sad.string(), 0, 0,
        {"no SDR root found", "--sdrroot"});
}

// ---------------------------------------------------------------------------------------------
// Hostile input: huge, deep, entity bombs, DTDs and external entities.

TEST_CASE("a file over the size limit is refused before parsing", "[malformed][too-large]") {
  const std::size_t overhead = padded_sad(0).size();
  TempDir dir;

  SECTION("one byte over") {
    const fs::path file = dir.path() / "huge.sad.xml";
    write_file(file, padded_sad(kMaxProfileBytes + 1 - overhead));
    REQUIRE(fs::file_size(file) == kMaxProfileBytes + 1);
    auto result = read_descriptor(file);
    const Error &error = error_of(result);
    REQUIRE(error.diagnostics().size() == 1);
    check(error.diagnostics().front(), "too-large", file.string(), 0, 0,
          {"the file is 8388609 bytes", "limited to 8388608 bytes"});

    ProfileLoader loader;
    auto validated = loader.validate(file);
    check(find_rule(error_of(validated), "too-large"), "too-large", loader_name(file), 0, 0, {});
  }
  SECTION("exactly at the limit is read") {
    const fs::path file = dir.path() / "limit.sad.xml";
    write_file(file, padded_sad(kMaxProfileBytes - overhead));
    REQUIRE(fs::file_size(file) == kMaxProfileBytes);
    auto result = read_descriptor(file);
    INFO((result ? std::string() : result.error().to_string()));
    REQUIRE(result.has_value());
    CHECK(std::get<SoftwareAssembly>(*result).id == "DCE:big");
  }
}

TEST_CASE("deeply nested elements fail cleanly", "[malformed][deep]") {
  // Far deeper than any profile: refused at the depth limit, fast, without exhausting the stack.
  constexpr std::size_t kDepth = 100000;
  TempDir dir;
  const fs::path file = dir.path() / "deep.sad.xml";
  std::string text = "<?xml version=\"1.0\"?>\n<softwareassembly id=\"DCE:deep\">";
  text.reserve(text.size() + kDepth * 7 + 32);
  for (std::size_t i = 0; i < kDepth; ++i)
    text += "<a>";
  for (std::size_t i = 0; i < kDepth; ++i)
    text += "</a>";
  text += "</softwareassembly>\n";
  write_file(file, text);

  const auto start = std::chrono::steady_clock::now();
  auto result = read_descriptor(file);
  const Error &error = error_of(result);
  for (const auto &d : error.diagnostics()) {
    INFO("diagnostic: " << to_string(d));
    CHECK((d.rule == "schema" || d.rule == "xml"));
    CHECK(d.where.file == file.string());
  }
  CHECK_THAT(error.to_string(), Contains("nest deeper than 64 levels"));
  // Refused at the limit rather than after reading all 100000 levels (which took seconds).
  CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(5));
  // The reader is still usable afterwards.
  auto next = read_descriptor(fixture("duplicate/property_id.prf.xml"));
  check(error_of(next).diagnostics().front(), "duplicate-id",
        fixture("duplicate/property_id.prf.xml").string(), 8, 53, {});
}

TEST_CASE("a billion laughs entity bomb fails fast", "[malformed][entities]") {
  const fs::path file = fixture("entities/billion_laughs.sad.xml");
  const auto start = std::chrono::steady_clock::now();
  auto result = read_descriptor(file);
  const auto elapsed = std::chrono::steady_clock::now() - start;
  // Refused either by the entity-expansion limit or because the DTD is never read; both are
  // well-formedness errors where the bomb is used.
  const Diagnostic &d = error_of(result).diagnostics().front();
  INFO("diagnostic: " << to_string(d));
  CHECK((d.rule == "xml" || d.rule == "schema"));
  CHECK(d.where.file == file.string());
  CHECK(d.where.line == 16);
  CHECK(elapsed < std::chrono::seconds(5));
}

TEST_CASE("a DOCTYPE naming a remote DTD is never fetched", "[malformed][entities]") {
  // example.invalid cannot resolve: if any DTD were fetched, these files would fail.
  const fs::path root = fixture("entities/remote_dtd");
  const fs::path sad = root / "dom/waveforms/app/app.sad.xml";
  ProfileLoader loader(root);
  auto result = loader.load_application(sad);
  INFO((result ? std::string() : result.error().to_string()));
  REQUIRE(result.has_value());
  CHECK(result->warnings.empty());
  REQUIRE(result->component_files.count("comp_spd") == 1);
  const auto &pkg = result->component_files.at("comp_spd");
  REQUIRE(pkg->properties != nullptr);
  CHECK(pkg->find_property("count") != nullptr);
}

TEST_CASE("an external entity is never read", "[malformed][entities]") {
  const fs::path file = fixture("entities/external_entity.sad.xml");
  REQUIRE(fs::is_regular_file(fixture("entities/secret.txt")));
  auto result = read_descriptor(file);
  // Refusing the file would be fine too; what must not happen is the secret in the model.
  if (result)
    CHECK(std::get<SoftwareAssembly>(*result).description.find("SECRET") == std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// No partial model; every independent error reported.

TEST_CASE("one dangling reference deep inside leaves no partial model", "[malformed][partial]") {
  const fs::path file = fixture("partial/dangling_deep.sad.xml");

  // The file is well-formed and schema-valid, so it reaches the SAD reader...
  auto document = read_xml_profile(file);
  INFO((document ? std::string() : document.error().to_string()));
  REQUIRE(document.has_value());

  // ...which returns an error, not a model with the bad path left out.
  auto sad = read_sad(*document);
  const Error &error = error_of(sad);
  REQUIRE(error.diagnostics().size() == 1);
  const Diagnostic &d = error.diagnostics().front();
  INFO("diagnostic: " << to_string(d));
  CHECK(d.rule == "dangling-ref");
  CHECK(d.where.file == file.string());
  CHECK(d.where.line == 49); // the <componentinstantiationref refid="ghost_1"/> itself
  CHECK_THAT(d.message,
             Contains("latency path \"to_nowhere\" names componentinstantiation \"ghost_1\""));

  auto descriptor = read_descriptor(file);
  CHECK_FALSE(descriptor.has_value());
}

TEST_CASE("independent errors in one file are all reported", "[malformed][partial]") {
  SECTION("reference errors") {
    const fs::path file = fixture("partial/several_errors.sad.xml");
    auto result = read_descriptor(file);
    const Error &error = error_of(result);
    REQUIRE(error.diagnostics().size() == 3);
    check(error.diagnostics()[0], "dangling-ref", file.string(), 11, 46, {"\"nothing_spd\""});
    check(error.diagnostics()[1], "duplicate-id", file.string(), 16, 44, {"\"comp_1\""});
    check(error.diagnostics()[2], "dangling-ref", file.string(), 20, 49, {"\"ghost_1\""});
  }
  SECTION("schema errors") {
    const fs::path file = fixture("partial/several_schema_errors.sad.xml");
    auto result = read_descriptor(file);
    const Error &error = error_of(result);
    REQUIRE(error.diagnostics().size() == 3);
    check(error.diagnostics()[0], "schema", file.string(), 11, 57, {"'colour'"});
    check(error.diagnostics()[1], "schema", file.string(), 12, 62, {"'first'"});
    check(error.diagnostics()[2], "schema", file.string(), 13, 32, {"'soon'"});
  }
}

TEST_CASE("a UTF-16 file is refused before any DTD in it is read", "[malformed][entities]") {
  TempDir dir;
  const fs::path file = dir.path() / "utf16.sad.xml";
  const std::string ascii = "<?xml version=\"1.0\" encoding=\"UTF-16\"?>\n"
                            "<!DOCTYPE softwareassembly [<!ENTITY a \"aaaaaaaaaa\">]>\n"
                            "<softwareassembly id=\"x\">&a;&a;</softwareassembly>\n";
  std::string utf16 = "\xFF\xFE"; // little-endian BOM, then each character and a zero byte
  for (char c : ascii) {
    utf16 += c;
    utf16 += '\0';
  }
  write_file(file, utf16);
  auto result = read_descriptor(file);
  check(error_of(result).diagnostics().front(), "encoding", file.string(), 1, 1,
        {"not UTF-8", "profiles must be UTF-8 text"});
}

TEST_CASE("a file name leaving the SDR root is refused", "[malformed][outside-sdrroot]") {
  TempDir dir;
  const fs::path sad = dir.path() / "sdr/dom/waveforms/app/app.sad.xml";
  fs::create_directories(sad.parent_path());
  write_file(sad, R"(<?xml version="1.0" encoding="UTF-8"?>
<softwareassembly id="DCE:escape" name="escape">
  <componentfiles>
    <componentfile id="f" type="SPD">
      <localfile name="/../../../../../../../../etc/hostname"/>
    </componentfile>
  </componentfiles>
  <partitioning>
    <componentplacement>
      <componentfileref refid="f"/>
      <componentinstantiation id="c"/>
    </componentplacement>
  </partitioning>
  <assemblycontroller><componentinstantiationref refid="c"/></assemblycontroller>
</softwareassembly>
)");
  ProfileLoader loader;
  auto app = loader.load_application(sad);
  const Diagnostic &d = find_rule(error_of(app), "outside-sdrroot");
  CHECK(d.where.line == 5);
  CHECK_THAT(d.message, Contains("lies outside the SDR root"));
}
