#include "profile/xml_reader.hpp"

#include "common/install_layout.hpp"

#include <dlfcn.h>
#include <malloc.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>

#include <fmt/format.h>

namespace rsca::profile {
namespace {

namespace fs = std::filesystem;

constexpr const char *kModuleName = "librsca_xml_reader.so";

// The folder of the file this code was loaded from: the program itself, or the runtime library
// (librsca_runtime.so) of a component built against an installed rsca, which may run from any
// folder (its package in a node's cache) while the runtime sits in the library folder.
fs::path own_object_folder() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void *>(&own_object_folder), &info) == 0 ||
      info.dli_fname == nullptr)
    return {};
  std::error_code ec;
  const auto file = fs::canonical(info.dli_fname, ec);
  return ec ? fs::path() : file.parent_path();
}

// Where the module is: $RSCA_XML_READER alone when set; else rsca's library folders as seen from
// the running program (an installed tree or the build tree), then `rsca/` beside the runtime
// library this code is in. No path of the build is compiled in: it would be a place the
// installed daemons load code from.
std::vector<fs::path> module_candidates() {
  if (const char *path = std::getenv("RSCA_XML_READER"); path != nullptr && *path != '\0')
    return {fs::path(path)};
  std::vector<fs::path> out;
  for (const auto &folder : layout::library_folders())
    out.push_back(folder / kModuleName);
  if (const auto folder = own_object_folder(); !folder.empty())
    out.push_back(folder / "rsca" / kModuleName);
  return out;
}

std::mutex g_mutex;
std::weak_ptr<XmlReader> g_reader; // guarded by g_mutex

} // namespace

Expected<std::shared_ptr<XmlReader>> XmlReader::acquire() {
  std::lock_guard lock(g_mutex);
  if (auto held = g_reader.lock())
    return held;
  std::string tried;
  for (const auto &candidate : module_candidates()) {
    void *handle =
        dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL | (kUnloads ? 0 : RTLD_NODELETE));
    if (handle == nullptr) {
      tried += fmt::format("\n  {}", dlerror());
      continue;
    }
    auto read = reinterpret_cast<ReadFunction>(dlsym(handle, "rsca_xml_reader_read"));
    if (read == nullptr) {
      tried += fmt::format("\n  {}: no rsca_xml_reader_read", candidate.string());
      dlclose(handle);
      continue;
    }
    auto reader = std::make_shared<XmlReader>(Token{}, handle, read);
    g_reader = reader;
    return reader;
  }
  return make_error({kModuleName, 0, 0}, "io",
                    fmt::format("cannot load the XML reader module:{}", tried));
}

bool XmlReader::loaded() {
  std::lock_guard lock(g_mutex);
  return !g_reader.expired();
}

XmlReader::~XmlReader() {
  // Serialised with acquire(), so a new load never overlaps this unload.
  std::lock_guard lock(g_mutex);
  dlclose(handle_);
  // Give the heap Xerces used (compiled schemas, readers) back to the system.
  malloc_trim(0);
}

Expected<XmlDocument> XmlReader::read(std::string_view text, const std::string &file) const {
  Expected<XmlDocument> out = make_error({file, 0, 0}, "xml", "the reader gave no result");
  read_(text, file, out);
  return out;
}

} // namespace rsca::profile
