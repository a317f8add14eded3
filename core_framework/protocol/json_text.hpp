// JSON text from outside the process (a request, a reply, a link's frame, an announcement, an
// event) made into a value: the one parse every such place uses, bounded.
//
// nlohmann's parser itself keeps its own stack, so it reads any nesting; but copying, comparing
// or dumping a value recurses once per level, and a body nested 100,000 deep (400 KB) overflowed
// the stack of whoever copied it (issue 37, defect 2). A text that nests deeper than the bound is
// refused here, before any value exists: no value deeper than the bound is ever built.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include <tl/expected.hpp>

#include "protocol/codec.hpp"

namespace rsca::protocol {

// Arrays and objects inside one another, at most: the XML reader's bound (profile/xml_reader).
inline constexpr std::size_t kMaxJsonDepth = 64;
// Bytes of text, at most: what a node's link carries in a frame (protocol/node_link.hpp), so that
// whatever a CLI may send through its node passes; a body of 2 million keys (30 MB) does not.
inline constexpr std::size_t kMaxJsonBytes = 16U << 20U;

// The value of `text`, or why not: "is N bytes, over the limit of M", "not valid JSON: …", or
// "nests deeper than N levels" (see nests_deeper). A scalar nests 0 levels, [] 1, {"a": [1]} 2.
// Its strings, lists and maps are bounded where a message decodes them (protocol/codec.hpp).
tl::expected<Json, std::string> parse_json(std::string_view text,
                                           std::size_t max_depth = kMaxJsonDepth);

// Whether `text` has arrays and objects nested more than `max_depth` deep. Linear, no allocation:
// strings are skipped, and a text that is not JSON is answered all the same (its parse fails).
bool nests_deeper(std::string_view text, std::size_t max_depth);

// `text` with every array and object nested deeper than `max_depth` left out (never built): what
// a refusal may still read of a text parse_json refused, such as the id of a request to answer.
// Discarded (Json::is_discarded) when it is not JSON.
Json parse_json_pruned(std::string_view text, std::size_t max_depth);

} // namespace rsca::protocol
