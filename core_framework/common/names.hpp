// Names that become parts of paths, control addresses and DDS partitions: an application's
// (installed or running), a component's, a port's, a device's, a node's. A name is one component
// of such a path, never a path itself, so that no name that reaches the domain (from a profile or
// from the network) can make it act outside what it owns.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include <tl/expected.hpp>

namespace rsca {

// Long enough for any real name, short enough to be a file name on every Linux file system.
inline constexpr std::size_t kMaxNameLength = 255;

// Why `name` is not a name, or nothing: empty, longer than kMaxNameLength bytes, "." or "..",
// starting with "." (the domain's own files), or holding a path separator ('/', '\') or a
// control character. `what` says what it names ("application name").
tl::expected<void, std::string> check_name(std::string_view what, std::string_view name);

// At most `max` characters of `text` for a message, marked where it was cut: an error quotes
// what it got without quoting megabytes of it.
std::string excerpt(std::string_view text, std::size_t max = 64);

} // namespace rsca
