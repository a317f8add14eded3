// Property values as SADs, DCDs and SPD dependencies write them (simpleref, structref, ...):
// text bound to a property id, checked against the PRF once that is known.
#pragma once

#include <string>
#include <variant>
#include <vector>

#include "common/diagnostic.hpp"

namespace rsca::profile {

struct SimpleRef {
  std::string refid;
  std::string value;
  SourceLocation where;
};

struct SimpleSequenceRef {
  std::string refid;
  std::vector<std::string> values;
  SourceLocation where;
};

struct StructRef {
  std::string refid;
  std::vector<std::variant<SimpleRef, SimpleSequenceRef>> members;
  SourceLocation where;
};

struct StructSequenceRef {
  std::string refid;
  std::vector<StructRef> values; // each <structvalue>, with refid empty
  SourceLocation where;
};

using PropertyRef = std::variant<SimpleRef, SimpleSequenceRef, StructRef, StructSequenceRef>;

const std::string &refid_of(const PropertyRef &ref);
const SourceLocation &location_of(const PropertyRef &ref);

} // namespace rsca::profile
