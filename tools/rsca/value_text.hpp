// How the CLI prints a property value: a long sequence or text summarised (its first items and
// its length), so that `rsca query` of a trace of thousands of numbers stays readable; whole when
// asked (--full; --json always prints values whole).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace rsca::cli {

// Sequences longer than this are summarised.
inline constexpr std::size_t kSummarisedItems = 8;
// Text longer than this is summarised.
inline constexpr std::size_t kSummarisedChars = 200;

// `value` as text: a string as it is, anything else as JSON; summarised unless `full`.
std::string value_text(const nlohmann::json &value, bool full);

} // namespace rsca::cli
