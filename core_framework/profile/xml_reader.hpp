// The validating XML reader, loaded only while profiles are being read.
//
// Xerces brings some forty shared libraries with it (curl, GnuTLS, Kerberos, LDAP, ICU...), about
// half of an idle node daemon's memory. So it lives in a module (librsca_xml_reader.so) that is
// loaded when the first XmlReader is acquired and unloaded when the last one is gone: a node
// daemon or a component reads its profiles at start and then runs without Xerces. A
// ProfileLoader holds a reader while it lives, so one loader's many files share one load.
#pragma once

#include <memory>
#include <string>
#include <string_view>

#include "common/diagnostic.hpp"
#include "profile/xml_document.hpp"

namespace rsca::profile {

class XmlReader {
public:
  // The loaded reader, loading it if nobody holds it. Fails when the module cannot be loaded.
  static Expected<std::shared_ptr<XmlReader>> acquire();
  // Whether the module is loaded now (some reader is held).
  static bool loaded();
  // Whether releasing the last reader takes Xerces out of the process. Not in sanitizer builds:
  // LeakSanitizer's thread tracer crashes on the stale thread-local storage entries an unloaded
  // library leaves in other threads, so there the module stays mapped (RTLD_NODELETE).
#ifdef RSCA_SANITIZE
  static constexpr bool kUnloads = false;
#else
  static constexpr bool kUnloads = true;
#endif

private:
  struct Token {
    explicit Token() = default;
  };

public:
  using ReadFunction = void (*)(std::string_view, const std::string &, Expected<XmlDocument> &);
  XmlReader(Token, void *handle, ReadFunction read_function)
      : handle_(handle), read_(read_function) {}
  ~XmlReader();
  XmlReader(const XmlReader &) = delete;
  XmlReader &operator=(const XmlReader &) = delete;

  // Validates `text` (a profile without its DOCTYPE) and builds its tree.
  Expected<XmlDocument> read(std::string_view text, const std::string &file) const;

private:
  void *handle_;
  ReadFunction read_;
};

} // namespace rsca::profile
