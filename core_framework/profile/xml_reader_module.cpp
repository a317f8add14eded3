// The Xerces side of profile reading, built as a module (librsca_xml_reader.so) that
// profile/xml_reader.cpp loads while profiles are being read and unloads afterwards: Xerces brings
// some forty libraries (curl, GnuTLS, Kerberos, ICU...) that a daemon or component process should
// not carry once its profiles are read. Everything here is reached through rsca_xml_reader_read.
#include "profile/xml_document.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <vector>

#include <fmt/format.h>
#include <xercesc/framework/MemBufInputSource.hpp>
#include <xercesc/framework/XMLGrammarPoolImpl.hpp>
#include <xercesc/sax/EntityResolver.hpp>
#include <xercesc/sax/Locator.hpp>
#include <xercesc/sax/SAXParseException.hpp>
#include <xercesc/sax2/Attributes.hpp>
#include <xercesc/sax2/DefaultHandler.hpp>
#include <xercesc/sax2/SAX2XMLReader.hpp>
#include <xercesc/sax2/XMLReaderFactory.hpp>
#include <xercesc/util/OutOfMemoryException.hpp>
#include <xercesc/util/PlatformUtils.hpp>
#include <xercesc/util/SecurityManager.hpp>
#include <xercesc/util/TransService.hpp>
#include <xercesc/util/XMLUni.hpp>
#include <xercesc/validators/common/Grammar.hpp>

namespace rsca::profile {

// Generated from schemas/*.xsd by cmake/RscaEmbed.cmake.
namespace schemas {
std::string_view embedded_file(std::string_view name);
}

// Declared here, defined below: the resolver serves the schemas compiled into this module.
std::string_view embedded_schema(std::string_view file_name);

namespace {

namespace x = xercesc;

constexpr std::string_view kRootSchema = "rsca.xsd";
constexpr std::size_t kMaxDiagnosticsPerFile = 20;
// No profile nests deeper than about ten levels; a deeper document is refused before its depth
// can cost time (Xerces' namespace lookups grow with depth) or stack (the tree is recursive).
constexpr std::size_t kMaxDepth = 64;

// The schema's own pattern facets, and what to tell a user whose value does not match one.
struct PatternMeaning {
  std::string_view facet;
  std::string_view expected;
};
constexpr PatternMeaning kPatternMeanings[] = {
    {"[0-9]+(\\.[0-9]+)?(ns|us|ms|s)", "a duration such as 10ms, 1.5s or 250us, or infinite"},
    {"[0-9]+(\\.[0-9]+)?(B|KiB|MiB|GiB|kB|MB|GB)", "a size such as 64MiB or 512kB"},
    {"[0-9]+(\\.[0-9]+)?(bps|kbps|Mbps|Gbps)", "a bit rate such as 10Mbps"},
    {"[+\\-]?[0-9]+", "an integer"},
};

// Xerces states some rules as the regular expression behind them; say what they mean instead.
std::string explain(std::string message) {
  // common.Blank: the content of an element that holds only attributes.
  constexpr std::string_view kBlank = "' which is not equal to length facet value '0'";
  if (message.starts_with("value '") && message.find(kBlank) != std::string::npos)
    return fmt::format("this element holds only attributes: text \"{}\" is not allowed in it",
                       message.substr(7, message.find('\'', 7) - 7));
  constexpr std::string_view kFacet = "does not match regular expression facet '";
  const auto at = message.find(kFacet);
  if (at == std::string::npos)
    return message;
  const std::string_view facet =
      std::string_view(message).substr(at + kFacet.size(), message.size() - at - kFacet.size() - 1);
  for (const auto &meaning : kPatternMeanings)
    if (facet.find(meaning.facet) != std::string_view::npos)
      return message.substr(0, at) + "is not " + std::string(meaning.expected);
  return message;
}

// The elements of rsca's extensions (docs/profiles.md, "RSCA extensions"), which REDHAWK does not
// have: their attributes are checked strictly.
constexpr std::string_view kRscaElements[] = {
    "timing", "qos", "filter", "latencyconstraints", "latencypath", "resourcedemand"};

constexpr std::string_view kProfileRoots =
    "softwareassembly (SAD), softpkg (SPD), softwarecomponent (SCD), properties (PRF), "
    "deviceconfiguration (DCD), domainmanagerconfiguration (DMD) or devicepkg (DPD)";

// Thrown from the content handler to stop a parse that must not go on; caught in read().
struct ParseStopped {
  Diagnostic diagnostic;
};
// Entity expansions allowed in one document: plenty for any profile, and a "billion laughs"
// document fails fast instead of exhausting memory.
constexpr XMLSize_t kEntityExpansionLimit = 10000;

// Xerces needs one process-wide initialisation before any use and a termination after the last.
struct XercesRuntime {
  XercesRuntime() { x::XMLPlatformUtils::Initialize(); }
  ~XercesRuntime() { x::XMLPlatformUtils::Terminate(); }
  XercesRuntime(const XercesRuntime &) = delete;
  XercesRuntime &operator=(const XercesRuntime &) = delete;
};

void ensure_xerces() {
  static XercesRuntime runtime;
}

class Utf8 {
public:
  Utf8() {
    x::XMLTransService::Codes code;
    transcoder_.reset(x::XMLPlatformUtils::fgTransService->makeNewTranscoderFor(
        "UTF-8", code, 16 * 1024, x::XMLPlatformUtils::fgMemoryManager));
  }
  std::string operator()(const XMLCh *text, XMLSize_t length) const {
    if (text == nullptr || length == 0)
      return {};
    x::TranscodeToStr out(text, length, transcoder_.get());
    return {reinterpret_cast<const char *>(out.str()), out.length()};
  }
  std::string operator()(const XMLCh *text) const {
    return (*this)(text, text == nullptr ? 0 : x::XMLString::stringLen(text));
  }

private:
  std::unique_ptr<x::XMLTranscoder> transcoder_;
};

// Serves the embedded schemas by file name and an empty document for anything else, so that
// DOCTYPE system ids and schema locations are resolved locally and nothing is ever fetched.
class LocalOnlyResolver final : public x::EntityResolver {
public:
  x::InputSource *resolveEntity(const XMLCh *const, const XMLCh *const system_id_text) override {
    std::string system_id = utf8_(system_id_text);
    std::string_view name = system_id;
    if (auto slash = name.find_last_of('/'); slash != std::string_view::npos)
      name.remove_prefix(slash + 1);
    std::string_view text = embedded_schema(name);
    // Xerces takes ownership of the returned source.
    return std::make_unique<x::MemBufInputSource>(reinterpret_cast<const XMLByte *>(text.data()),
                                                  text.size(), std::string(name).c_str())
        .release();
  }

private:
  Utf8 utf8_;
};

// Collects located diagnostics; Xerces reports the position it had reached, which for element
// problems is the end of the start tag.
class DiagnosticCollector final : public x::ErrorHandler {
public:
  explicit DiagnosticCollector(std::string file) : file_(std::move(file)) {}

  void warning(const x::SAXParseException &) override {}
  void error(const x::SAXParseException &e) override { add(e, "schema"); }
  void fatalError(const x::SAXParseException &e) override { add(e, "xml"); }
  void resetErrors() override {
    error_ = Error();
    warnings_.clear();
    undeclared_.clear();
  }
  // Whether the root element has been seen yet: a problem before it is a problem with the root.
  void set_root_seen(bool seen) { root_seen_ = seen; }

  const Error &error() const { return error_; }
  std::vector<Diagnostic> take_warnings() { return std::move(warnings_); }
  void add(Diagnostic d) {
    if (error_.diagnostics().size() < kMaxDiagnosticsPerFile)
      error_.add(std::move(d));
  }

private:
  void add(const x::SAXParseException &e, const char *rule) {
    std::string message = explain(utf8_(e.getMessage()));
    const SourceLocation where{file_, static_cast<int>(e.getLineNumber()),
                               static_cast<int>(e.getColumnNumber())};
    if (auto tolerated = tolerated_by_redhawk(message)) {
      if (warnings_.size() < kMaxDiagnosticsPerFile)
        warnings_.push_back({where, "unknown-attribute", std::move(*tolerated), Severity::Warning});
      return;
    }
    constexpr std::string_view kUndeclared = "no declaration found for element '";
    if (message.starts_with(kUndeclared)) {
      std::string name = message.substr(kUndeclared.size(), message.find('\'', kUndeclared.size()) -
                                                                kUndeclared.size());
      if (!root_seen_)
        message = fmt::format("<{}> is not the root of a domain profile: expected {}", name,
                              kProfileRoots);
      else
        message = fmt::format("<{}> is not an element rsca knows here", name);
      undeclared_.push_back(std::move(name));
    } else if (is_consequence_of_undeclared(message)) {
      return; // the parent's content model fails only because of a child already reported
    }
    add(Diagnostic{where, rule, std::move(message)});
  }

  // REDHAWK's parsers skip attributes they do not know, and real profiles carry some (IDE
  // leftovers, attributes of later REDHAWK versions): such an attribute is read with a warning
  // and ignored. Nothing else the schemas refuse is tolerated here.
  static std::optional<std::string> tolerated_by_redhawk(const std::string &message) {
    constexpr std::string_view kAttribute = "attribute '";
    constexpr std::string_view kUndeclared = "' is not declared for element '";
    if (!message.starts_with(kAttribute))
      return std::nullopt;
    const auto name_end = message.find(kUndeclared);
    if (name_end == std::string::npos)
      return std::nullopt;
    const std::string name = message.substr(kAttribute.size(), name_end - kAttribute.size());
    const auto element_at = name_end + kUndeclared.size();
    const std::string element =
        message.substr(element_at, message.find('\'', element_at) - element_at);
    // rsca's own elements are no REDHAWK's: a misspelt attribute there is a mistake to refuse
    // (a <qos leese="..."> would otherwise silently keep the default lease).
    if (std::find(std::begin(kRscaElements), std::end(kRscaElements), element) !=
        std::end(kRscaElements))
      return std::nullopt;
    return fmt::format("attribute {} is not one rsca knows on <{}>: ignored, as REDHAWK does", name,
                       element);
  }

  bool is_consequence_of_undeclared(const std::string &message) const {
    if (message.find("is not allowed for content model") == std::string::npos)
      return false;
    for (const auto &name : undeclared_)
      if (message.find("'" + name + "'") != std::string::npos)
        return true;
    return false;
  }

  std::string file_;
  Error error_;
  std::vector<Diagnostic> warnings_;
  Utf8 utf8_;
  bool root_seen_ = false;
  std::vector<std::string> undeclared_;
};

// Builds the XmlElement tree from SAX events.
class TreeBuilder final : public x::DefaultHandler {
public:
  void setDocumentLocator(const x::Locator *const locator) override { locator_ = locator; }
  void set_collector(DiagnosticCollector *collector) { collector_ = collector; }

  void startElement(const XMLCh *const, const XMLCh *const local_name, const XMLCh *const,
                    const x::Attributes &attributes) override {
    if (collector_ != nullptr)
      collector_->set_root_seen(true);
    if (open_.size() >= kMaxDepth)
      throw ParseStopped{
          {{file_, line(), column()},
           "xml",
           fmt::format("elements nest deeper than {} levels; no profile does", kMaxDepth)}};
    XmlElement element;
    element.name = utf8_(local_name);
    if (locator_ != nullptr) {
      element.line = static_cast<int>(locator_->getLineNumber());
      element.column = static_cast<int>(locator_->getColumnNumber());
    }
    element.attributes.reserve(attributes.getLength());
    for (XMLSize_t i = 0; i < attributes.getLength(); ++i)
      element.attributes.emplace_back(utf8_(attributes.getLocalName(i)),
                                      utf8_(attributes.getValue(i)));
    if (open_.empty()) {
      root_ = std::move(element);
      open_.push_back(&root_);
      return;
    }
    // Only the innermost open element grows, so pointers to its ancestors stay valid.
    open_.back()->children.push_back(std::move(element));
    open_.push_back(&open_.back()->children.back());
  }

  void endElement(const XMLCh *const, const XMLCh *const, const XMLCh *const) override {
    open_.pop_back();
  }

  void characters(const XMLCh *const chars, const XMLSize_t length) override {
    if (!open_.empty())
      open_.back()->text += utf8_(chars, length);
  }

  XmlElement take_root() { return std::move(root_); }
  void reset(std::string file) {
    root_ = XmlElement();
    open_.clear();
    file_ = std::move(file);
  }

private:
  int line() const { return locator_ != nullptr ? static_cast<int>(locator_->getLineNumber()) : 0; }
  int column() const {
    return locator_ != nullptr ? static_cast<int>(locator_->getColumnNumber()) : 0;
  }

  const x::Locator *locator_ = nullptr;
  DiagnosticCollector *collector_ = nullptr;
  std::string file_;
  XmlElement root_;
  std::vector<XmlElement *> open_;
  Utf8 utf8_;
};

void set_validating_features(x::SAX2XMLReader &reader) {
  reader.setFeature(x::XMLUni::fgSAX2CoreNameSpaces, true);
  reader.setFeature(x::XMLUni::fgSAX2CoreValidation, true);
  reader.setFeature(x::XMLUni::fgXercesDynamic, false);
  reader.setFeature(x::XMLUni::fgXercesSchema, true);
  reader.setFeature(x::XMLUni::fgXercesIdentityConstraintChecking, true);
  // REDHAWK's profiles carry SCA DOCTYPE lines; the DTD is neither fetched nor used, the
  // schemas are the only grammar.
  reader.setFeature(x::XMLUni::fgXercesLoadExternalDTD, false);
  reader.setFeature(x::XMLUni::fgXercesSkipDTDValidation, true);
  reader.setFeature(x::XMLUni::fgXercesDisableDefaultEntityResolution, true);
}

// The schemas, compiled once per process and shared read-only by every reader.
class SchemaCache {
public:
  SchemaCache() {
    ensure_xerces();
    pool_ = std::make_unique<x::XMLGrammarPoolImpl>(x::XMLPlatformUtils::fgMemoryManager);
    std::unique_ptr<x::SAX2XMLReader> loader(
        x::XMLReaderFactory::createXMLReader(x::XMLPlatformUtils::fgMemoryManager, pool_.get()));
    set_validating_features(*loader);
    loader->setFeature(x::XMLUni::fgXercesSchemaFullChecking, true);
    LocalOnlyResolver resolver;
    DiagnosticCollector collector{std::string(kRootSchema)};
    loader->setEntityResolver(&resolver);
    loader->setErrorHandler(&collector);
    std::string_view text = embedded_schema(kRootSchema);
    x::MemBufInputSource source(reinterpret_cast<const XMLByte *>(text.data()), text.size(),
                                std::string(kRootSchema).c_str());
    try {
      if (loader->loadGrammar(source, x::Grammar::SchemaGrammarType, true) == nullptr)
        collector.add({{std::string(kRootSchema), 0, 0}, "schema", "the schema did not load"});
    } catch (...) {
      collector.add({{std::string(kRootSchema), 0, 0}, "schema", "the schema did not load"});
    }
    load_error_ = collector.error();
    pool_->lockPool();
  }

  x::XMLGrammarPool *pool() const { return pool_.get(); }
  // Non-empty when the built-in schemas themselves are broken (a build defect).
  const Error &load_error() const { return load_error_; }

private:
  std::unique_ptr<x::XMLGrammarPool> pool_;
  Error load_error_;
};

const SchemaCache &schema_cache() {
  static SchemaCache cache;
  return cache;
}

// One validating reader per thread: creating a Xerces reader costs more than a small parse.
class ProfileReader {
public:
  ProfileReader() : cache_(schema_cache()) {
    reader_.reset(
        x::XMLReaderFactory::createXMLReader(x::XMLPlatformUtils::fgMemoryManager, cache_.pool()));
    set_validating_features(*reader_);
    reader_->setFeature(x::XMLUni::fgXercesUseCachedGrammarInParse, true);
    reader_->setFeature(x::XMLUni::fgXercesLoadSchema, false);
    security_.setEntityExpansionLimit(kEntityExpansionLimit);
    reader_->setProperty(x::XMLUni::fgXercesSecurityManager, &security_);
    reader_->setEntityResolver(&resolver_);
    reader_->setContentHandler(&builder_);
  }

  Expected<XmlDocument> read(std::string_view text, const std::string &file) {
    if (!cache_.load_error().empty())
      return tl::unexpected(cache_.load_error());
    if (text.find_first_not_of(" \t\r\n") == std::string_view::npos)
      return make_error({file, 1, 1}, "xml", "the file is empty: expected an XML profile");
    // Profiles are UTF-8 (as every SCA tool writes them). Refusing UTF-16/32 up front also means
    // every DOCTYPE reaches blank_doctype, so no entity declaration survives to be expanded.
    if (text.find('\0') != std::string_view::npos)
      return make_error({file, 1, 1}, "encoding",
                        "the file is not UTF-8 (it holds NUL bytes): profiles must be UTF-8 text");

    DiagnosticCollector collector(file);
    reader_->setErrorHandler(&collector);
    builder_.reset(file);
    builder_.set_collector(&collector);
    x::MemBufInputSource source(reinterpret_cast<const XMLByte *>(text.data()), text.size(),
                                file.c_str());
    try {
      reader_->parse(source);
    } catch (const ParseStopped &stopped) {
      collector.add(stopped.diagnostic);
    } catch (const x::SAXParseException &) {
      // Already reported through the collector.
    } catch (const x::OutOfMemoryException &) {
      collector.add({{file, 0, 0}, "xml", "out of memory while parsing"});
    } catch (const x::XMLException &e) {
      collector.add({{file, static_cast<int>(e.getSrcLine()), 0}, "xml", utf8_(e.getMessage())});
    } catch (...) {
      collector.add({{file, 0, 0}, "xml", "the parser failed for an unknown reason"});
    }
    reader_->setErrorHandler(nullptr);
    builder_.set_collector(nullptr);
    if (!collector.error().empty()) {
      builder_.reset({});
      return tl::unexpected(collector.error());
    }
    return XmlDocument{file, builder_.take_root(), collector.take_warnings(), false};
  }

private:
  const SchemaCache &cache_;
  std::unique_ptr<x::SAX2XMLReader> reader_;
  x::SecurityManager security_;
  LocalOnlyResolver resolver_;
  TreeBuilder builder_;
  Utf8 utf8_;
};

// Readers kept for reuse: creating a Xerces reader costs more than a small parse. A pool rather
// than one reader per thread, because a thread_local with a destructor would pin the module in
// memory for as long as its thread lives.
class ReaderPool {
public:
  std::unique_ptr<ProfileReader> take() {
    std::lock_guard lock(mutex_);
    if (free_.empty())
      return std::make_unique<ProfileReader>();
    auto reader = std::move(free_.back());
    free_.pop_back();
    return reader;
  }
  void give_back(std::unique_ptr<ProfileReader> reader) {
    std::lock_guard lock(mutex_);
    free_.push_back(std::move(reader));
  }

private:
  std::mutex mutex_;
  std::vector<std::unique_ptr<ProfileReader>> free_;
};

ReaderPool &reader_pool() {
  // The cache first, so that it (and Xerces) is destroyed after the pool's readers.
  schema_cache();
  static ReaderPool pool;
  return pool;
}

} // namespace

std::string_view embedded_schema(std::string_view file_name) {
  return schemas::embedded_file(file_name);
}

} // namespace rsca::profile

// The module's one entry point (resolved with dlsym): validates `text` and builds its tree.
extern "C" void rsca_xml_reader_read(std::string_view text, const std::string &file,
                                     rsca::Expected<rsca::profile::XmlDocument> &out) {
  auto &pool = rsca::profile::reader_pool();
  auto reader = pool.take();
  out = reader->read(text, file);
  pool.give_back(std::move(reader));
}
