// A property value as the command line writes it (`rsca configure APP name=VALUE`), read into the
// form its PRF definition has, so that bind_property types and checks it as it does a SAD's:
//   simple          name=value               (the text as it is)
//   simplesequence  name=[1,2,3]  or  name=1,2,3   (name=[] is empty)
//   struct          name={member=value,member2=[1,2]}
//   structsequence  name=[{member=1},{member=2}]
// An item may be quoted, "a, b", to hold , [ ] { } = or spaces (\" and \\ inside quotes).
#pragma once

#include <string>
#include <string_view>

#include <tl/expected.hpp>

#include "profile/prf.hpp"
#include "profile/property_refs.hpp"

namespace rsca::profile {

// The ref `text` gives for `definition`; the error says what is malformed, naming the property.
tl::expected<PropertyRef, std::string> ref_from_argument(const PropertyDefinition &definition,
                                                         std::string_view text);

} // namespace rsca::profile
