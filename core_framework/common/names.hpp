// The rule for names that travel in requests and become parts of addresses, topics and paths
// (applications, components, ports, nodes, devices, connection ids), and bounded excerpts of
// untrusted text for messages. A request from the network is untrusted: a name is checked before
// it is used or kept, and an error quotes at most an excerpt of what it got.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "common/diagnostic.hpp"

namespace rsca {

// The longest name, in bytes (a file name's limit on Linux).
inline constexpr std::size_t kMaxNameLength = 255;
// The longest excerpt of untrusted text a message quotes, in bytes.
inline constexpr std::size_t kExcerptLength = 40;

// Whether `name` can be a name: not empty, at most kMaxNameLength bytes, not "." or "..", not
// starting with '.' (the domain's own files, e.g. its staging folder), no '/' or '\' (the
// separators of APP/COMPONENT and of paths) and no control characters: a name is one component of
// a path or an address, never a path. `what` names it in the message ("the application", "the
// port"). The rule is "name"; the location is `what`.
Expected<void> check_name(std::string_view what, std::string_view name);

// `text` for a message: at most `max` bytes, control characters as \xNN, and when cut, "..." and
// how long it was. Never splits a UTF-8 sequence.
std::string excerpt(std::string_view text, std::size_t max = kExcerptLength);

// The one of `names` a misspelling of which `name` likely is (a small edit distance, letter case
// ignored), for a message's "did you mean"; empty when none is close.
std::string closest_name(std::string_view name, const std::vector<std::string> &names);

} // namespace rsca
